// The application layer: identify() and check() over files and columns in memory, options that
// validate themselves, and results that own what they hold.

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "momentid/check.hpp"
#include "momentid/identify.hpp"
#include "momentid/json.hpp"
#include "momentid/simulate.hpp"
#include "test_support.hpp"

namespace {

using momentid::testing::error_from;
using momentid::testing::model_file;

// A simulated Duffing record in a CSV file, removed at the end of the test.
struct DuffingFile {
  momentid::Model model = model_file("duffing.mom");
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("momentid_test_app_" + std::to_string(::getpid()) + ".csv");
  explicit DuffingFile(std::size_t samples, std::size_t runs = 1) {
    momentid::SimulationOptions options;
    options.inputs = {momentid::InputSpec::parse("ma:K=10,w=0.1,sigma=20", "test")};
    options.samples = samples;
    options.runs = runs;
    momentid::simulate_to_file(model, options, path.string(), momentid::DataWriter::Format::kCsv);
  }
  ~DuffingFile() { std::filesystem::remove(path); }
};

// The columns of a CSV file without metadata lines, read back whole.
std::vector<std::vector<double>> read_columns(const std::string& path,
                                              const std::vector<std::string>& names) {
  auto reader = momentid::DataReader::open(path, {.names = names});
  std::vector<std::vector<double>> columns(names.size());
  momentid::DataBlock block;
  while (reader->next(block, 4096)) {
    for (std::size_t r = 0; r < block.rows; ++r) {
      for (std::size_t c = 0; c < names.size(); ++c) {
        columns[c].push_back(block.values[r * names.size() + c]);
      }
    }
  }
  return columns;
}

// Displacement and force as arrays without a time column: y = sin(0.05 n), x = cos(0.07 n).
struct SineArrays {
  std::vector<double> y, x;
  momentid::MemoryData data;
  SineArrays(const SineArrays&) = delete;  // data points into y and x
  explicit SineArrays(std::size_t rows) : y(rows), x(rows) {
    for (std::size_t n = 0; n < rows; ++n) {
      y[n] = std::sin(0.05 * static_cast<double>(n));
      x[n] = std::cos(0.07 * static_cast<double>(n));
    }
    data.rows = rows;
    data.name = "arrays";
    data.columns = {{"y", y.data()}, {"x", x.data()}};
  }
};

}  // namespace

// A result holding only a model and the estimates of its parameters, in declaration order.
momentid::IdentifyResult result_with(const momentid::Model& model,
                                     const std::vector<double>& estimates) {
  momentid::IdentifyResult r;
  r.model = std::make_shared<const momentid::Model>(model);
  for (std::size_t p = 0; p < estimates.size(); ++p) {
    r.estimate.least_squares.parameters.push_back({model.parameters()[p].name, estimates[p]});
  }
  return r;
}

TEST_SUITE("app") {
  TEST_CASE("a fixed parameter is known: the others are estimated with it, in both methods") {
    const DuffingFile file(50000);
    const auto source = momentid::DataSource::file(file.path.string());
    for (const bool lagged : {false, true}) {
      momentid::IdentifyOptions options;
      if (lagged) options.lags = std::pair{3, 150};
      const momentid::IdentifyResult free = momentid::identify(file.model, source, options);
      options.fixed = {{"k", 4.0}};
      const momentid::IdentifyResult fixed = momentid::identify(file.model, source, options);
      const auto& p = fixed.parameters();
      REQUIRE(p.size() == 3);
      CHECK(p[1].fixed);
      CHECK(p[1].estimate == 4.0);
      CHECK(p[1].std_error == 0);
      CHECK(!p[0].fixed);
      // Knowing k, the others agree with the free fit.
      for (std::size_t i : {0UL, 2UL}) {
        const auto& f = free.parameters()[i];
        const std::string method = lagged ? "lagged " : "zero-lag ";
        MESSAGE(method << p[i].name << ": free " << f.estimate << " +- " << f.std_error
                       << ", k fixed " << p[i].estimate << " +- " << p[i].std_error);
        CHECK(p[i].std_error > 0);
        CHECK(std::abs(p[i].estimate - f.estimate) < 3 * f.std_error);
      }
      CHECK(std::isnan(fixed.estimate.least_squares.correlation[1][0]));
      CHECK(momentid::json_value(fixed)["parameters"]["k"]["fixed"] == true);
      CHECK(momentid::format_text(fixed).find("fixed\n") != std::string::npos);
    }
  }

  TEST_CASE("a record split into files gives the estimates of the same runs in one file") {
    const DuffingFile whole(4000, 2);
    // The runs of the whole file, each in a file of its own.
    std::ifstream in(whole.path);
    std::string line, header;
    std::vector<std::string> metadata;
    std::vector<std::ostringstream> parts(2);
    while (std::getline(in, line)) {
      if (line.starts_with("#")) {
        metadata.push_back(line);
      } else if (header.empty()) {
        header = line.substr(0, line.rfind(','));  // without `run`
      } else {
        const std::size_t comma = line.rfind(',');
        parts[std::stoul(line.substr(comma + 1)) - 1] << line.substr(0, comma) << "\n";
      }
    }
    std::vector<std::string> paths;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      paths.push_back(whole.path.string() + ".part" + std::to_string(k));
      std::ofstream out(paths.back());
      for (const std::string& m : metadata) out << m << "\n";
      out << header << "\n" << parts[k].str();
    }
    // Least squares: the optimal weighting comes from the batches, which differ (below).
    const momentid::IdentifyOptions ls{.weighting = momentid::Weighting::kLeastSquares};
    const auto a =
        momentid::identify(whole.model, momentid::DataSource::file(whole.path.string()), ls);
    const auto b = momentid::identify(whole.model, momentid::DataSource::files(paths), ls);
    for (const std::string& p : paths) std::filesystem::remove(p);
    CHECK(b.data.runs == 2);
    for (std::size_t i = 0; i < a.parameters().size(); ++i) {
      // (The standard errors differ: each file is a shard whose stretches the batches take
      // whole, so the batches of two files are cut elsewhere than those of one file.)
      CHECK(a.parameters()[i].estimate ==
            doctest::Approx(b.parameters()[i].estimate).epsilon(1e-12));
    }
  }

  TEST_CASE("a parameter fixed in the model file is fixed as by the option, whose value wins") {
    const DuffingFile file(20000);
    const auto source = momentid::DataSource::file(file.path.string());
    const momentid::Model declared = momentid::parse_model(
        "model duffing\nstate y, v\ninput x\nparam c, k = 4 fixed, eps\ny' = v\n"
        "v' = -c*v - k*y - eps*y^3 + x\n",
        "fixed.mom");
    const auto estimates = [](const momentid::IdentifyResult& r) {
      std::vector<double> out;
      for (const auto& p : r.parameters()) out.push_back(p.estimate);
      return out;
    };
    const momentid::IdentifyResult by_file = momentid::identify(declared, source, {});
    CHECK(by_file.parameters()[1].fixed);
    CHECK(estimates(by_file) ==
          estimates(momentid::identify(file.model, source, {.fixed = {{"k", 4.0}}})));
    const momentid::IdentifyResult overridden =
        momentid::identify(declared, source, {.fixed = {{"k", 3.5}}});
    CHECK(overridden.parameters()[1].estimate == 3.5);
    CHECK(estimates(overridden) ==
          estimates(momentid::identify(file.model, source, {.fixed = {{"k", 3.5}}})));
    const auto e = error_from<momentid::UsageError>([&] {
      momentid::identify(declared, source, {.fixed = {{"c", 1.0}, {"eps", 1.0}}});
    });
    CHECK(std::string(e.what()) ==
          "fixed: every parameter of model duffing is fixed (by fixed or in the model file): "
          "there is nothing to estimate");
  }

  TEST_CASE("equations whose every term carries an unknown parameter are refused") {
    // m*v' = -c*v - k*y + b*x holds as well for 2m, 2c, 2k, 2b: all estimates would be 0.
    const momentid::Model scaled = momentid::parse_model(
        "model s\nstate y, v\ninput x\nparam m, c, k, b\ny' = v\nm*v' = -c*v - k*y + b*x\n",
        "s.mom");
    const auto e =
        error_from<momentid::ModelError>([&] { momentid::IdentifyOptions{}.validate(scaled); });
    CHECK(std::string(e.what()) ==
          "s.mom:6:1: every term of equation 2 carries an unknown parameter (m, c, k, b), so the "
          "data determine them only up to a common factor: give one of them a value (a constant "
          "in the model, or fixed)");
    // A fixed one sets the scale; so does a known term in another equation that shares one.
    CHECK_NOTHROW(momentid::IdentifyOptions{.fixed = {{"m", 1.0}}}.validate(scaled));
    const momentid::Model shared = momentid::parse_model(
        "model s\nstate y, v, w\ninput x\nparam m, c, k\ny' = v\nm*v' = -k*y + x\n"
        "m*w' = -c*w\n",
        "s.mom");
    CHECK_NOTHROW(momentid::IdentifyOptions{}.validate(shared));
  }

  TEST_CASE("the identified model is printed with the estimates substituted") {
    const momentid::Model duffing = model_file("duffing.mom");
    CHECK(momentid::identified_equations(result_with(duffing, {0.5, 4, 1.25})) ==
          std::vector<std::string>{"y' = v", "v' = -4*y - 0.5*v - 1.25*y^3 + x"});
    // A parameter before the derivative divides the rest; a constant comes last; two
    // derivatives in one equation stay on the left.
    const momentid::Model model = momentid::parse_model(
        "model m\nstate y, v, w\ninput x\nparam m, c, b\ny' = v\n"
        "m*v' = -c*v - y + 2*x*y + b\nv' + 2*w' = -w + x\n",
        "m.mom");
    CHECK(momentid::identified_equations(result_with(model, {2, 0.5, 0.1})) ==
          std::vector<std::string>{"y' = v", "v' = -0.5*y - 0.25*v + y*x + 0.05",
                                   "v' + 2*w' = -w + x"});
    momentid::IdentifyResult deficient = result_with(duffing, {0.5, 4, 1});
    deficient.estimate.status = momentid::Status::kRankDeficient;
    CHECK(momentid::identified_equations(deficient).empty());
  }

  TEST_CASE("identify gives the same numbers from columns in memory as from the file") {
    const DuffingFile file(20000, 2);
    const std::vector<std::string> names{"t", "y", "v", "x", "run"};
    const auto columns = read_columns(file.path.string(), names);
    momentid::MemoryData data;
    data.rows = columns[0].size();
    for (std::size_t c = 0; c < names.size(); ++c) {
      data.columns.push_back({names[c], columns[c].data()});
    }
    data.metadata.add_line({{"input-hold", "zoh"}, {"dt", "0.01"}});
    const momentid::IdentifyOptions options{
        .degree = 3, .batches = 20, .weighting = momentid::Weighting::kGmm};
    const auto from_file =
        momentid::identify(file.model, momentid::DataSource::file(file.path.string()), options);
    const auto from_memory =
        momentid::identify(file.model, momentid::DataSource::memory(std::move(data)), options);
    CHECK(from_memory.data.rows == 40000);
    CHECK(from_memory.data.runs == 2);
    REQUIRE(from_file.estimate.status == momentid::Status::kOk);
    // The same values through the same accumulation: equal to the last bit.
    for (std::size_t p = 0; p < 3; ++p) {
      CHECK(from_memory.parameters()[p].estimate == from_file.parameters()[p].estimate);
      CHECK(from_memory.parameters()[p].std_error == from_file.parameters()[p].std_error);
    }
    CHECK(from_memory.data.time_step == from_file.data.time_step);
  }

  TEST_CASE("a corner for states formed from a column is warned of where none is formed") {
    const DuffingFile file(20000, 1);
    const auto result = momentid::identify(
        file.model, momentid::DataSource::file(file.path.string()), {.integrate_corner = 2.0});
    CHECK(!result.integration);
    const std::vector<std::string> all = momentid::warnings(result);
    CHECK(std::count(all.begin(), all.end(),
                     "--integrate-corner has no effect: no state was formed from a derivative's "
                     "column (the equations need none that the record lacks; --integrate names "
                     "states to form)") == 1);
  }

  TEST_CASE("columns of a row-major matrix are read in place through their stride") {
    const DuffingFile file(5000);
    const auto columns = read_columns(file.path.string(), {"y", "v", "x"});
    std::vector<double> matrix;
    for (std::size_t r = 0; r < columns[0].size(); ++r) {
      for (const auto& column : columns) matrix.push_back(column[r]);
    }
    momentid::MemoryData data;
    data.rows = columns[0].size();
    data.columns = {
        {"y", matrix.data(), 3}, {"v", matrix.data() + 1, 3}, {"x", matrix.data() + 2, 3}};
    data.metadata.add_line({{"model", "duffing"}, {"dt", "0.01"}, {"input-hold", "zoh"}});
    const auto strided = momentid::identify(file.model, momentid::DataSource::memory(data));
    const auto from_file =
        momentid::identify(file.model, momentid::DataSource::file(file.path.string()));
    for (std::size_t p = 0; p < 3; ++p) {
      CHECK(strided.parameters()[p].estimate == from_file.parameters()[p].estimate);
    }
    CHECK(strided.data.time_step == 0.01);
  }

  TEST_CASE(
      "one value that decides a channel's moments is named with its row, in identify and check") {
    const DuffingFile file(5000);
    std::vector<std::vector<double>> columns =
        read_columns(file.path.string(), {"t", "y", "v", "x"});
    const auto identify_with = [&](double spike) {
      std::vector<double> y = columns[1];
      if (spike != 0) y[1234] = spike;
      momentid::MemoryData data;
      data.rows = y.size();
      data.columns = {{"t", columns[0].data()},
                      {"y", y.data()},
                      {"v", columns[2].data()},
                      {"x", columns[3].data()}};
      data.metadata.add_line({{"model", "duffing"}, {"input-hold", "zoh"}});
      return momentid::identify(file.model, momentid::DataSource::memory(data));
    };
    const auto warned = [](const momentid::IdentifyResult& r, const std::string& text) {
      const auto w = momentid::format_text(r);
      return w.find(text) != std::string::npos;
    };
    const auto clean = identify_with(0);
    CHECK(clean.estimate.status == momentid::Status::kOk);
    CHECK_FALSE(warned(clean, "one sample decides"));
    // Its square beyond doubles: the estimate is undone, and the cause named.
    const auto overflow = identify_with(1e300);
    CHECK(overflow.estimate.status != momentid::Status::kOk);
    CHECK(warned(overflow,
                 "'y' has a value of magnitude 1e+300 at row 1235 of the record that "
                 "has a square beyond the range of doubles: one sample decides every "
                 "moment of it"));
    CHECK_FALSE(warned(overflow, "parameters along :"));
    // A spike of 10^4 (the record's rms is about 0.2): never 'ok'.
    const auto spike = identify_with(1e4);
    CHECK(momentid::status(spike) != momentid::Status::kOk);
    CHECK(warned(spike,
                 "'y' has a value of magnitude 10000 at row 1235 of the record that carries "
                 "100% of the channel's sum of squares"));
  }

  TEST_CASE("a value that is not finite in memory is located at its row and column") {
    const std::vector<double> y{1, 2, std::numeric_limits<double>::quiet_NaN(), 4};
    const std::vector<double> x{0, 1, 0, 1};
    momentid::MemoryData data;
    data.rows = 4;
    data.name = "arrays";
    data.columns = {{"x", x.data()}, {"y", y.data()}};
    const momentid::Model model = model_file("kozin_4_1a.mom");
    const auto e = error_from<momentid::DataError>(
        [&] { momentid::identify(model, momentid::DataSource::memory(data), {.batches = 2}); });
    CHECK(std::string(e.what()) ==
          "arrays:3:2: column 'y': expected a number (a missing value? missing drop-row or "
          "split-run passes over it), found 'nan'");
  }

  TEST_CASE("a metadata dt in memory that is not a positive number is refused") {
    const std::vector<double> y{1, 2, 3, 4};
    momentid::MemoryData data;
    data.rows = 4;
    data.columns = {{"y", y.data()}, {"x", y.data()}};
    data.metadata.add_line({{"dt", "-1"}});
    const auto e = error_from<momentid::DataError>([&] {
      momentid::identify(model_file("kozin_4_1a.mom"), momentid::DataSource::memory(data),
                         {.batches = 2});
    });
    CHECK(std::string(e.what()) ==
          "<memory>:0:0: metadata dt: expected a positive number, found '-1'");
  }

  TEST_CASE("options out of range are refused by the library, naming the option") {
    const momentid::Model model = model_file("duffing.mom");
    const auto source = momentid::DataSource::file("unused.csv");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::identify(model, source, {.batches = 0});
                      }).what()) == "batches: expected a number from 2 to 10000, found 0");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::identify(model, source, {.degree = 13});
                      }).what()) ==
          "degree: expected 0 (automatic) or a number from 1 to 12, found 13");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::identify(model, source, {.input_shift = 1001});
                      }).what()) ==
          "input_shift: expected a number from -1000 to 1000, found 1001");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::identify(model, source, {.record = {.columns = {{"w", "y"}}}});
                      }).what()) == "columns: 'w' is not a state or input of model duffing");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::check(source, &model, {.lags = 0});
                      }).what()) == "lags: expected a number from 1 to 1000, found 0");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::identify(model, source, {.integrate = {"x"}});
                      }).what()) == "integrate: 'x' is not a state of model duffing");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::identify(model, source,
                                           {.integrate = {"y"}, .integrate_corner = -1.0});
                      }).what()) == "integrate_corner: expected a positive frequency in Hz");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::identify(
                            model, source,
                            {.method = momentid::Method::kZeroLag, .integrate = {"y"}});
                      }).what()) ==
          "method: the zero-lag equations do not read states formed by integrate");

    momentid::SimulationOptions simulation;
    simulation.inputs.resize(1);
    simulation.dt = 0;
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::simulate_to_file(model, simulation, "unused.csv",
                                                   momentid::DataWriter::Format::kCsv);
                      }).what()) == "dt: expected a number from 1e-9 to 1e6, found 0");
    CHECK_FALSE(std::filesystem::exists("unused.csv"));
    simulation.dt = 0.01;
    simulation.inputs.clear();
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::simulate_to_file(model, simulation, "unused.csv",
                                                   momentid::DataWriter::Format::kCsv);
                      }).what()) == "inputs: model duffing needs 1 input processes, found 0");
  }

  TEST_CASE("a result stays valid after the model it was computed from is gone") {
    const DuffingFile file(5000);
    std::optional<momentid::IdentifyResult> result;
    {
      const momentid::Model copy = file.model;
      result = momentid::identify(copy, momentid::DataSource::file(file.path.string()));
    }
    CHECK(result->zero_lag->system->model == result->model.get());
    CHECK(momentid::format_text(*result).starts_with("model duffing, data "));
    CHECK(momentid::json_value(*result)["moments"].contains("E[y^2]"));
  }

  TEST_CASE("the JSON text reads back as the value, with each fit's objective and covariance") {
    const DuffingFile file(20000);
    const auto source = momentid::DataSource::file(file.path.string());
    const momentid::IdentifyResult r = momentid::identify(file.model, source, {.degree = 3});
    REQUIRE(r.estimate.optimal);
    const nlohmann::ordered_json value = momentid::json_value(r);
    // Equal as values: every number the same double, every key in its place.
    CHECK(nlohmann::ordered_json::parse(momentid::format_json(r)) == value);
    const nlohmann::ordered_json& diagnostics = value["diagnostics"];
    const auto check_fit = [](const momentid::Fit& fit, const nlohmann::ordered_json& json) {
      CHECK(json["objective"].get<double>() == fit.objective);
      CHECK(json["error_dof"].get<double>() == fit.dof);
      const auto covariance = fit.covariance();
      REQUIRE(json["covariance"].size() == covariance.size());
      for (std::size_t i = 0; i < covariance.size(); ++i) {
        for (std::size_t j = 0; j < covariance.size(); ++j) {
          CHECK(json["covariance"][i][j].get<double>() == covariance[i][j]);
        }
      }
    };
    check_fit(*r.estimate.optimal, diagnostics);
    check_fit(r.estimate.least_squares, diagnostics["least_squares"]);
    CHECK(diagnostics["objective"].get<double>() > 0);
    // Least squares as the main fit: its figures are the diagnostics' own.
    const momentid::IdentifyResult ls = momentid::identify(
        file.model, source, {.degree = 3, .weighting = momentid::Weighting::kLeastSquares});
    const nlohmann::ordered_json ls_value = momentid::json_value(ls);
    CHECK_FALSE(ls_value.contains("least_squares"));
    CHECK_FALSE(ls_value["diagnostics"].contains("least_squares"));
    check_fit(ls.estimate.least_squares, ls_value["diagnostics"]);
  }

  TEST_CASE("check without a model takes every column but t and run as a channel") {
    const DuffingFile file(2000, 2);
    const momentid::CheckResult r =
        momentid::check(momentid::DataSource::file(file.path.string()), nullptr, {.lags = 3});
    REQUIRE(r.data.channels.size() == 3);
    CHECK(r.data.channels[0].name == "y");
    CHECK(r.data.channels[2].name == "x");
    CHECK(r.data.runs == 2);
    CHECK(r.data.channels[0].autocorrelation.size() == 3);
    CHECK(r.identities.empty());
  }

  TEST_CASE("the autocorrelation of short runs is their pairs' covariance about the mean") {
    // Three runs of four rows: the pairs at lag l leave out each run's first l
    // values as leads and its last l as lagged ones, so their means are not the record's.
    const momentid::testing::Directory dir("momentid_test_short_runs");
    const std::vector<std::vector<double>> runs = {{0, 1, 2, 6}, {2, 4, 7, 9}, {1, 2, 3, 9}};
    {
      std::ofstream out(dir / "runs.csv");
      out << "t,x,run\n";
      for (std::size_t r = 0; r < runs.size(); ++r) {
        for (std::size_t n = 0; n < runs[r].size(); ++n) {
          out << 0.1 * static_cast<double>(n) << "," << runs[r][n] << "," << r + 1 << "\n";
        }
      }
    }
    const momentid::CheckResult result =
        momentid::check(momentid::DataSource::file(dir / "runs.csv"), nullptr, {.lags = 2});
    double sum = 0, count = 0;
    for (const auto& run : runs) {
      for (double x : run) sum += x, ++count;
    }
    const double mean = sum / count;
    double variance = 0;
    for (const auto& run : runs) {
      for (double x : run) variance += (x - mean) * (x - mean) / count;
    }
    const std::vector<double>& rho = result.data.channels[0].autocorrelation;
    REQUIRE(rho.size() == 2);
    for (std::size_t lag = 1; lag <= 2; ++lag) {
      double products = 0, pairs = 0;
      for (const auto& run : runs) {
        for (std::size_t n = lag; n < run.size(); ++n) {
          products += (run[n] - mean) * (run[n - lag] - mean);
          ++pairs;
        }
      }
      CHECK(rho[lag - 1] == doctest::Approx(products / pairs / variance).epsilon(1e-12));
      CHECK(std::abs(rho[lag - 1]) <= 1);
    }
  }

  TEST_CASE("check's JSON value holds the result's numbers, null where there is none") {
    SineArrays arrays(500);
    std::fill(arrays.x.begin(), arrays.x.end(), 1.0);  // constant: no autocorrelation
    const momentid::Model model = model_file("duffing.mom");
    const auto source = momentid::DataSource::memory(arrays.data);
    for (const momentid::Model* with : {static_cast<const momentid::Model*>(nullptr), &model}) {
      CAPTURE(with != nullptr);
      const momentid::CheckResult r = momentid::check(source, with, {.lags = 4});
      const nlohmann::ordered_json value = momentid::json_value(r);
      CHECK(nlohmann::ordered_json::parse(momentid::format_json(r)) == value);
      CHECK(value["data"] == "arrays");
      CHECK(value["rows"] == 500);
      CHECK(value["runs"] == 1);
      CHECK(value["dt"].is_null());  // neither a time column nor metadata
      CHECK(value["lags"] == 4);
      CHECK(value["with_model"] == (with != nullptr));
      CHECK(value["missing_inputs"].get<std::vector<std::string>>() == r.missing_inputs);
      CHECK(value["missing_states"].get<std::vector<std::string>>() == r.missing_states);
      CHECK(value["warnings"].get<std::vector<std::string>>() == r.warnings);
      REQUIRE(value["channels"].size() == 2);
      for (const momentid::ChannelStatistics& c : r.data.channels) {
        CAPTURE(c.name);
        const nlohmann::ordered_json& json = value["channels"][c.name];
        CHECK(json["input"] == c.is_input);
        CHECK(json["mean"].get<double>() == c.mean);
        CHECK(json["variance"].get<double>() == c.variance);
        REQUIRE(json["autocorrelation"].size() == 4);
        for (std::size_t l = 0; l < 4; ++l) {
          const double rho = c.autocorrelation[l];
          CHECK((std::isfinite(rho) ? json["autocorrelation"][l].get<double>() == rho
                                    : json["autocorrelation"][l].is_null()));
        }
        CHECK(json["correlation_time"] == c.correlation_time);
        CHECK((c.noise_variance ? json["noise_variance"].get<double>() == *c.noise_variance
                                : json["noise_variance"].is_null()));
        CHECK((c.noise_fraction() ? json["noise_fraction"].get<double>() == *c.noise_fraction()
                                  : json["noise_fraction"].is_null()));
      }
      const nlohmann::ordered_json& x = value["channels"]["x"];
      CHECK(x["variance"].get<double>() == 0);
      CHECK(x["autocorrelation"][0].is_null());
      CHECK(x["noise_fraction"].is_null());
      CHECK(value["channels"]["y"]["noise_fraction"].is_number());
      REQUIRE(value["identities"].size() == r.identities.size());
      for (std::size_t i = 0; i < r.identities.size(); ++i) {
        CHECK(value["identities"][i]["identity"] == r.identities[i].identity);
        CHECK(value["identities"][i]["violation"].get<double>() == r.identities[i].violation);
        CHECK(value["identities"][i]["z"].get<double>() == r.identities[i].z);
      }
    }
  }

  TEST_CASE("the lagged equations need the sample interval and take no multipliers") {
    const SineArrays arrays(1000);
    const momentid::Model model = model_file("duffing.mom");
    const auto source = momentid::DataSource::memory(arrays.data);
    CHECK(std::string(error_from<momentid::DataError>([&] {
                        momentid::identify(model, source, {.batches = 2});
                      }).what()) ==
          "arrays:1:1: the lagged equations need the sample interval: give the data a 't' "
          "column or a dt in the metadata");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::identify(model, source, {.degree = 3, .batches = 2});
                      }).what()) ==
          "multipliers and a degree choose zero-lag equations, but the data lack v: the lagged "
          "equations take instruments instead");
  }

  TEST_CASE("check leaves out a state that the data show only as a derivative") {
    const momentid::Model model = model_file("duffing.mom");
    const SineArrays arrays(500);
    const momentid::CheckResult r =
        momentid::check(momentid::DataSource::memory(arrays.data), &model);
    CHECK(r.missing_states == std::vector<std::string>{"v"});
    CHECK(r.missing_inputs.empty());
    REQUIRE(r.data.channels.size() == 2);
    CHECK(r.data.channels[0].name == "y");
    CHECK(r.data.channels[1].name == "x");
    CHECK(momentid::format_text(r).find("state v is not in the file") != std::string::npos);
  }
}
