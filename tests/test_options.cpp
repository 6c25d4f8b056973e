// The options that several commands share: how to read a record (RecordOptions) and parameter
// values by name (ParameterValues).

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>

#include "momentid/record_options.hpp"
#include "momentid/simulate.hpp"
#include "test_support.hpp"

namespace {

using momentid::RecordOptions;
using momentid::UsageError;
using momentid::testing::error_from;
using momentid::testing::model_file;

// What validate() throws for `options`, "field: message", after checking that the error names
// the field.
std::string refusal(const RecordOptions& options, const momentid::Model* model,
                    const std::string& field) {
  const UsageError e = error_from<UsageError>([&] { options.validate(model); });
  CHECK(e.option() == field);
  return e.what();
}

}  // namespace

TEST_SUITE("options") {
  TEST_CASE("a record's dt must be a positive finite number, with or without a model") {
    const momentid::Model model = model_file("duffing.mom");
    for (const double dt : {0.0, -0.01, std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::quiet_NaN()}) {
      CHECK(refusal({.dt = dt}, nullptr, "dt") == "dt: expected a positive number");
      CHECK(refusal({.dt = dt}, &model, "dt") == "dt: expected a positive number");
    }
    CHECK_NOTHROW(RecordOptions{.dt = 0.01}.validate(&model));
    // Where the equations' powers of dt would leave the normal numbers (1e-320: 1/dt^2 is
    // infinite), it is refused with the range.
    CHECK(refusal({.dt = 1e-320}, &model, "dt") ==
          "dt: expected a sample interval from 1e-12 to 1e+12, found 1e-320");
    CHECK(refusal({.dt = 1e13}, nullptr, "dt") ==
          "dt: expected a sample interval from 1e-12 to 1e+12, found 1e+13");
    CHECK_NOTHROW(RecordOptions{.dt = 1e-12}.validate(&model));
  }

  TEST_CASE("a record's columns map the model's variables or t, checked when there is a model") {
    const momentid::Model model = model_file("duffing.mom");
    const RecordOptions options{.columns = {{"w", "y"}}};
    CHECK(refusal(options, &model, "columns") ==
          "columns: 'w' is not a state or input of model duffing");
    CHECK_NOTHROW(options.validate(nullptr));
    CHECK_NOTHROW(
        RecordOptions{.columns = {{"t", "time"}, {"v", "velocity"}, {"x", "force"}}}.validate(
            &model));
  }

  TEST_CASE("a column mapped from a state's derivative is declared as a measured statement would") {
    const momentid::Model model = model_file("duffing.mom");
    RecordOptions options{.columns = {{"v'", "accel"}, {"x", "force"}}};
    const momentid::Model with = momentid::declare_derivative_columns(model, options);
    REQUIRE(with.measured_derivatives().size() == 1);
    CHECK(with.measured_derivatives()[0].name == "accel");
    CHECK(with.measured_derivatives()[0].state == 1);  // v
    CHECK(options.columns ==
          std::map<std::string, std::string>{{"accel", "accel"}, {"x", "force"}});
    CHECK_NOTHROW(options.validate(&with));
    // y'' through y' = v is the same; a column name that cannot be a variable gives v_dot.
    RecordOptions odd{.columns = {{"y''", "Accel (m/s^2)"}}};
    const momentid::Model second = momentid::declare_derivative_columns(model, odd);
    CHECK(second.measured_derivatives()[0].name == "v_dot");
    CHECK(odd.columns == std::map<std::string, std::string>{{"v_dot", "Accel (m/s^2)"}});
    // A model that declares the column keeps its name for it.
    const momentid::Model declared = model_file("duffing_accelerometer.mom");
    RecordOptions mapped{.columns = {{"y''", "accel"}}};
    CHECK(momentid::declare_derivative_columns(declared, mapped).measured_derivatives().size() ==
          1);
    CHECK(mapped.columns == std::map<std::string, std::string>{{"a", "accel"}});
    const auto refused = [&](std::map<std::string, std::string> columns, const momentid::Model& m) {
      RecordOptions o{.columns = std::move(columns)};
      const UsageError e =
          error_from<UsageError>([&] { momentid::declare_derivative_columns(m, o); });
      CHECK(e.option() == "columns");
      return std::string(e.what());
    };
    CHECK(refused({{"x'", "a"}}, model) ==
          "columns: x'=a: x is not a state of model duffing (a column may hold a state's "
          "derivative)");
    CHECK(refused({{"v'''", "a"}}, model) ==
          "columns: v'''=a: a measured column holds a state's first or second derivative (v' or "
          "y''), found order 3");
    CHECK(refused({{"y'", "a"}}, model) ==
          "columns: y'=a: y' = v (equation 1): a column holding y' holds v, which a record gives "
          "as the state's own column (--columns \"v=COLUMN\")");
    CHECK(refused({{"v'", "accel"}, {"a", "accel"}}, declared) ==
          "columns: v'=accel and a=accel name the same channel, a");
  }

  TEST_CASE("a record's metadata declare its derivative columns to a model that lacks them") {
    const momentid::Model model = model_file("duffing.mom");
    const std::vector<double> values(4, 0.0);
    momentid::MemoryData data;
    for (const char* name : {"y", "x", "acc"}) data.columns.push_back({name, values.data()});
    data.rows = values.size();
    // As simulate writes it for models/duffing_accelerometer.mom, and another model's column.
    data.metadata.add_line({{"measured.acc", "y''"}, {"measured.q", "w'"}});
    const momentid::DataSource source = momentid::DataSource::memory(data);
    RecordOptions options;
    const momentid::Model with = momentid::declare_derivative_columns(model, options, source);
    REQUIRE(with.measured_derivatives().size() == 1);
    CHECK(with.measured_derivatives()[0].name == "acc");
    CHECK(with.measured_derivatives()[0].state == 1);
    // A model with its own column for v', or a column given for it, keeps that.
    RecordOptions given{.columns = {{"v'", "other"}}};
    CHECK(
        momentid::declare_derivative_columns(model, given, source).measured_derivatives()[0].name ==
        "other");
    RecordOptions own;
    const momentid::Model declared = model_file("duffing_accelerometer.mom");
    CHECK(momentid::declare_derivative_columns(declared, own, source)
              .measured_derivatives()[0]
              .name == "a");
    CHECK(own.columns.empty());
  }

  TEST_CASE("parameter values by name become the model's values in order, nominal where absent") {
    const momentid::Model model = model_file("duffing.mom");  // c = 0.5, k = 4, eps = 1
    const auto values = momentid::parameter_vector(
        model, {{"eps", momentid::ParameterValue::exact("0.1")}, {"c", 0.25}});
    REQUIRE(values.size() == 3);
    CHECK(values[0] == GiNaC::numeric(0.25));  // a double as it is
    CHECK(values[1] == 4);
    CHECK(values[2] == GiNaC::numeric(1, 10));  // a decimal exact
    CHECK(momentid::parse_parameter_values(model, {"k=+2.5e-1"}).at("k").decimal == "+2.5e-1");
    CHECK(momentid::parse_parameter_values(model, {"k=+2.5e-1"}).at("k").value == 0.25);
  }

  TEST_CASE("an unknown or missing parameter is named") {
    const momentid::Model model = model_file("duffing.mom");
    const UsageError unknown = error_from<UsageError>([&] {
      momentid::parameter_vector(model, {{"zz", 1.0}}, "parameters");
    });
    CHECK(unknown.option() == "parameters");
    CHECK(std::string(unknown.what()) ==
          "parameters: 'zz' is not a parameter of model duffing (parameters: c, k, eps)");
    const momentid::Model bare =
        momentid::parse_model("model bare\nstate y\nparam a\ny' = -a*y\n", "bare.mom");
    const momentid::ModelError missing =
        error_from<momentid::ModelError>([&] { momentid::parameter_vector(bare, {}); });
    CHECK(std::string(missing.what()) ==
          "bare.mom:3:7: parameter 'a' has no value: give a nominal value in the model or "
          "parameters a=VALUE");
    // A front end spells the field its own way: the command line's flag is --set.
    CHECK(missing.text([](const std::string& field) {
      return field == "parameters" ? "--set" : "--" + field;
    }) == "bare.mom:3:7: parameter 'a' has no value: give a nominal value in the model or --set "
          "a=VALUE");
  }
}
