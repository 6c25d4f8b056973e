// The options that several commands share: how to read a record (RecordOptions).

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>

#include "momentid/record_options.hpp"
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
}
