// The replay of recorded inputs and `validate`: interpolation, exact reproduction, fit figures
// against their theoretical values, the chosen skip, correlation checks and blow-ups.

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>

#include "momentid/json.hpp"
#include "momentid/validate.hpp"
#include "test_support.hpp"

namespace momentid {
namespace {

using testing::error_from;
using testing::model_file;
using testing::options_for;
using testing::Recorder;

// A simulated record held in memory: t, then the chosen model variables by name.
struct MemoryRecord {
  std::vector<std::vector<double>> columns;
  MemoryData data;
  MemoryRecord(const Model& model, const Recorder& recorder, const std::vector<std::string>& names,
               const std::string& hold) {
    columns.push_back(recorder.column(0));
    data.columns.push_back({"t", nullptr, 1});
    for (const std::string& name : names) {
      const auto v = static_cast<std::size_t>(model.variable_index(name));
      columns.push_back(recorder.column(v + 1));
      data.columns.push_back({name, nullptr, 1});
    }
    for (std::size_t c = 0; c < columns.size(); ++c) data.columns[c].values = columns[c].data();
    data.rows = recorder.rows.size();
    data.metadata.add_line({{"input-hold", hold}});
  }
  DataSource source() const { return DataSource::memory(data); }
};

Recorder simulated(const Model& model, const SimulationOptions& options,
                   const std::vector<double>& noise_sd = {}) {
  Recorder recorder(model.channel_count());
  simulate(model, options, recorder, noise_sd);
  return recorder;
}

SimulationOptions duffing_options(const Model& model, std::size_t samples) {
  SimulationOptions options = options_for(model, samples, 7);
  options.inputs[0] = InputSpec::parse("ma:K=10,w=0.1,sigma=20", "--input");
  return options;
}

ValidateOptions with_parameters(const Model& model, const std::vector<std::string>& set) {
  ValidateOptions options;
  options.replay.parameters = momentid::parse_parameter_values(model, set);
  return options;
}

TEST_SUITE("validate") {
  // The signal at the middle of each interval between samples.
  std::vector<double> midpoints(const std::vector<double>& u, Interpolation method) {
    const Interpolator half(method, {0.5});
    std::vector<double> out;
    for (std::size_t n = 0; n + 1 < u.size(); ++n) out.push_back(half(u, n, 0));
    return out;
  }

  TEST_CASE("each interpolation gives a sampled sinusoid the documented midpoint gain") {
    for (const double w : {0.2 * M_PI, 0.5 * M_PI, 0.8 * M_PI}) {
      std::vector<double> u;
      for (int n = 0; n < 200; ++n) u.push_back(std::cos(w * n + 0.3));
      const auto hold = midpoints(u, Interpolation::kHold);
      const auto line = midpoints(u, Interpolation::kLinear);
      const auto cubic = midpoints(u, Interpolation::kCubic);
      const auto sinc = midpoints(u, Interpolation::kSinc);
      REQUIRE(cubic.size() == 199);
      const double cubic_gain = (9 * std::cos(w / 2) - std::cos(3 * w / 2)) / 8;
      for (std::size_t n = 24; n + 25 < u.size(); ++n) {
        const double exact = std::cos(w * (n + 0.5) + 0.3);
        CHECK(hold[n] == u[n]);
        CHECK(std::abs(line[n] - std::cos(w / 2) * exact) < 1e-12);
        CHECK(std::abs(cubic[n] - cubic_gain * exact) < 1e-12);
        CHECK(std::abs(sinc[n] - exact) < 3e-7);
      }
    }
  }

  TEST_CASE("the band-limited interpolation is exact to 1e-6 at any fraction of the interval") {
    const double w = 0.6 * M_PI;
    std::vector<double> u;
    for (int n = 0; n < 100; ++n) u.push_back(std::sin(w * n));
    const Interpolator at(Interpolation::kSinc, {0.125, 0.25, 0.75, 0.875});
    for (std::size_t k = 0; k < 4; ++k) {
      const double f = 0.125 * (k < 2 ? k + 1 : k + 4);
      CHECK(std::abs(at(u, 50, k) - std::sin(w * (50 + f))) < 1e-6);
    }
  }

  TEST_CASE("intervals near the ends take the widest stencil that fits") {
    // A quadratic: the cubic and the three-point stencils are exact for it, at any fraction.
    std::vector<double> u;
    for (int n = 0; n < 40; ++n) u.push_back(1 + 2.0 * n - 0.25 * n * n);
    for (const Interpolation method : {Interpolation::kCubic, Interpolation::kSinc}) {
      const Interpolator at(method, {0.3, 0.5});
      for (std::size_t n : {0UL, 1UL, 2UL, 36UL, 37UL, 38UL}) {
        for (std::size_t k = 0; k < 2; ++k) {
          const double x = n + (k == 0 ? 0.3 : 0.5);
          CHECK(at(u, n, k) == doctest::Approx(1 + 2 * x - 0.25 * x * x).epsilon(1e-12));
        }
      }
    }
    CHECK(midpoints({1.0, 3.0}, Interpolation::kSinc) == std::vector<double>{2.0});
  }

  TEST_CASE("a record of held inputs is reproduced bit for bit with its own parameters") {
    const Model model = model_file("duffing.mom");
    const Recorder recorder = simulated(model, duffing_options(model, 3000));
    const MemoryRecord record(model, recorder, {"y", "v", "x"}, "zoh");
    ReplayOptions options;
    options.parameters = {};  // the nominal values
    const Replay replay = momentid::replay(model, record.source(), options);
    REQUIRE(replay.interpolation == std::vector<Interpolation>{Interpolation::kHold});
    REQUIRE(replay.simulated.size() == 1);
    CHECK(replay.simulated[0][0] == recorder.column(1));
    CHECK(replay.simulated[0][1] == recorder.column(2));
    CHECK(replay.initial_how == std::vector<std::string>{"its first sample", "its first sample"});
  }

  TEST_CASE("a multisine record is reproduced through band-limited interpolation") {
    // The simulator evaluates the multisine exactly at every stage; the replay sees its samples
    // only, ten per period of the highest line. Compared after the first 1000 rows (50 s, a
    // dozen decay times), where the start's short stencils no longer show, and before the
    // last 50, whose stencils are short too.
    const Model model = model_file("duffing.mom");
    SimulationOptions options = options_for(model, 4000, 3);
    options.dt = 0.05;
    options.inputs[0] = InputSpec::parse("multisine:f1=0.05,f2=2,lines=40,rms=5", "--input");
    const Recorder recorder = simulated(model, options);
    const MemoryRecord record(model, recorder, {"y", "v", "x"}, "sample");
    ReplayOptions replay_options;
    replay_options.parameters = {};  // the nominal values
    replay_options.substeps = 1;     // as the simulator integrated: only the inputs differ
    const std::vector<double> y = recorder.column(1);
    double spread = 0, worst_sinc = 0, worst_cubic = 0;
    for (double v : y) spread = std::max(spread, std::abs(v));
    for (const Interpolation method : {Interpolation::kSinc, Interpolation::kCubic}) {
      replay_options.interpolation = method;
      const Replay replay = momentid::replay(model, record.source(), replay_options);
      double worst = 0;
      for (std::size_t n = 1000; n + 50 < y.size(); ++n) {
        worst = std::max(worst, std::abs(replay.simulated[0][0][n] - y[n]));
      }
      (method == Interpolation::kSinc ? worst_sinc : worst_cubic) = worst / spread;
    }
    MESSAGE("largest error relative to the largest |y|: sinc " << worst_sinc << ", cubic "
                                                               << worst_cubic);
    CHECK(worst_sinc < 1e-6);
    CHECK(worst_sinc < worst_cubic);
  }

  TEST_CASE("the true parameters fit above 99.9% without a velocity column, 20% off well below") {
    const Model model = model_file("duffing.mom");
    const Recorder recorder = simulated(model, duffing_options(model, 20000));
    const MemoryRecord record(model, recorder, {"y", "x"}, "zoh");
    const ValidateResult truth = validate(model, record.source(), with_parameters(model, {}));
    REQUIRE(truth.outputs.size() == 1);
    CHECK(truth.replay.initial_how[1].find("y' at the start") == 0);
    CHECK(truth.outputs[0].fit > 99.9);
    CHECK(truth.warnings.empty());
    const ValidateResult off =
        validate(model, record.source(), with_parameters(model, {"c=0.6", "k=4.8", "eps=1.2"}));
    MESSAGE("fit with the truth " << truth.outputs[0].fit << "%, 20% off " << off.outputs[0].fit
                                  << "%");
    CHECK(off.outputs[0].fit < 80);
    REQUIRE(off.outputs[0].autocorrelation);
    CHECK(off.outputs[0].autocorrelation->outside() > 20);
  }

  TEST_CASE("a velocity read from noisy displacements at the start is fitted to the first rows") {
    const Model model = model_file("duffing.mom");
    SimulationOptions options = duffing_options(model, 20000);
    options.noise = {{"y", 0.02}};
    const Recorder recorder = simulated(model, options, noise_standard_deviations(model, options));
    const MemoryRecord record(model, recorder, {"y", "x"}, "zoh");
    const Replay fitted = replay(model, record.source(), {});
    const double truth = recorder.column(2)[0];
    // The cubic through the first seven samples alone gave 7.65 where the record's v is 2.33.
    MESSAGE("v at the start: truth " << truth << ", fitted " << fitted.initial[0][1]);
    CHECK(fitted.initial_how[1].find("y' at the start (a cubic fitted to the first 7 samples "
                                     "of y), then fitted by least squares to the first ") == 0);
    const std::vector<double> v = recorder.column(2);
    const double spread =
        std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0) / v.size());
    CHECK(std::abs(fitted.initial[0][1] - truth) < 0.02 * spread);
    // A record with the velocity's column starts from it, unfitted.
    const MemoryRecord measured(model, recorder, {"y", "v", "x"}, "zoh");
    const Replay direct = replay(model, measured.source(), {});
    CHECK(direct.initial_how[1] == "its first sample");
  }

  TEST_CASE("center removes a sensor offset before the simulation and says how much") {
    const Model model = model_file("duffing.mom");
    const Recorder recorder = simulated(model, duffing_options(model, 20000));
    MemoryRecord record(model, recorder, {"y", "x"}, "zoh");
    const std::vector<double> y = recorder.column(1);
    const double mean = std::accumulate(y.begin(), y.end(), 0.0) / static_cast<double>(y.size());
    constexpr double kOffset = 0.3;  // about 0.4 of y's standard deviation
    for (double& value : record.columns[1]) value += kOffset;
    ValidateOptions options = with_parameters(model, {});
    const ValidateResult offset = validate(model, record.source(), options);
    CHECK(offset.centered.empty());
    options.center = {"y"};
    const ValidateResult centered = validate(model, record.source(), options);
    REQUIRE(centered.centered.size() == 1);
    CHECK(centered.centered.at("y") == doctest::Approx(kOffset + mean).epsilon(1e-12));
    MESSAGE("fit with the offset " << offset.outputs[0].fit << "%, centered "
                                   << centered.outputs[0].fit << "%");
    // The true mean of y is zero: what is left after centering is the sample mean's error.
    CHECK(centered.outputs[0].fit > 99);
    CHECK(offset.outputs[0].fit < 80);
    CHECK(format_text(centered).find("\nmeans removed (--center): y ") != std::string::npos);
    CHECK(json_value(centered)["centered"]["y"].get<double>() == centered.centered.at("y"));
    CHECK_FALSE(json_value(offset).contains("centered"));
    options.center = {"q"};
    const UsageError e = error_from<UsageError>([&] { validate(model, record.source(), options); });
    CHECK(e.option() == "center");
    CHECK(std::string(e.what()) == "center: 'q' is not a state or input of model duffing");
  }

  TEST_CASE("with 1% sensor noise the fit is its theoretical value and the checks pass") {
    const Model model = model_file("duffing.mom");
    SimulationOptions options = duffing_options(model, 100000);
    options.noise = {{"y", 0.01}};
    const std::vector<double> sd = noise_standard_deviations(model, options);
    const Recorder recorder = simulated(model, options, sd);
    const MemoryRecord record(model, recorder, {"y", "v", "x"}, "zoh");
    const ValidateResult result = validate(model, record.source(), with_parameters(model, {}));
    const OutputFit& y = result.outputs[0];
    // Over the compared rows: the error is the noise, sd[0] per sample.
    const std::vector<double> measured = recorder.column(1);
    const std::size_t skip = result.skip[0];
    const double count = static_cast<double>(measured.size() - skip);
    const double mean =
        std::accumulate(measured.begin() + static_cast<long>(skip), measured.end(), 0.0) / count;
    double spread = 0;
    for (std::size_t n = skip; n < measured.size(); ++n) {
      spread += (measured[n] - mean) * (measured[n] - mean);
    }
    const double theory = 100 * (1 - sd[0] * std::sqrt(count) / std::sqrt(spread));
    MESSAGE("fit " << y.fit << "%, theoretical " << theory << "%");
    CHECK(std::abs(y.fit - theory) < 0.1);
    CHECK(std::abs(y.rms / sd[0] - 1) < 0.02);
    // Nothing but white noise is left: 1% of the lags fall outside by chance.
    REQUIRE(y.autocorrelation);
    CHECK(y.autocorrelation->outside() <= 2);
    REQUIRE(y.cross.size() == 1);
    CHECK(y.cross[0].outside() <= 3);
    CHECK(std::abs(y.rms_rest / y.rms_start - 1) < 0.1);
  }

  TEST_CASE("the noise band: noise inside, k 1% off outside, inside as an estimate one error off") {
    const Model model = model_file("duffing.mom");
    SimulationOptions simulation = duffing_options(model, 50000);
    simulation.noise = {{"y", 0.01}, {"v", 0.01}};
    const Recorder recorder =
        simulated(model, simulation, noise_standard_deviations(model, simulation));
    const MemoryRecord record(model, recorder, {"y", "v", "x"}, "zoh");
    const ValidateResult truth = validate(model, record.source(), with_parameters(model, {}));
    const NoiseBand& band = truth.noise_band;
    REQUIRE(band.compared);
    CHECK_FALSE(band.with_errors);
    CHECK(band.input_noise == std::vector<double>{0.0});  // the held force is exact
    REQUIRE(band.outputs.size() == 2);
    for (const NoiseBand::Output& output : band.outputs) {
      MESSAGE(output.name << ": " << output.error << " of " << output.limit);
      CHECK(output.inside());
      CHECK(output.simulations.size() == NoiseBand::kSimulations);
    }
    CHECK(truth.consistent);
    CHECK(truth.warnings.empty());
    // k 1% off: the error it leaves is far beyond the band, and the fit still near 99%.
    ValidateOptions off = with_parameters(model, {"k=4.04"});
    const ValidateResult wrong = validate(model, record.source(), off);
    CHECK(wrong.noise_band.outside() == 2);
    CHECK_FALSE(wrong.consistent);
    MESSAGE("k 1% off: fit " << wrong.outputs[0].fit << "%, error "
                             << wrong.noise_band.outputs[0].error << " of "
                             << wrong.noise_band.outputs[0].limit);
    CHECK(wrong.outputs[0].fit > 90);
    CHECK(wrong.warnings.back().find("v: the error beyond its white noise is ") == 0);
    // The same values as an estimate one standard error off: inside the band it widens.
    off.covariance = {{0, 0, 0}, {0, 0.04 * 0.04, 0}, {0, 0, 0}};
    const ValidateResult estimated = validate(model, record.source(), off);
    CHECK(estimated.noise_band.with_errors);
    CHECK(estimated.noise_band.outside() == 0);
    CHECK(estimated.consistent);
    CHECK(estimated.noise_band.outputs[0].estimates > wrong.noise_band.outputs[0].error);
    // A covariance of another size is refused.
    off.covariance = {{1}};
    const UsageError e = error_from<UsageError>([&] { validate(model, record.source(), off); });
    CHECK(e.option() == "covariance");
    CHECK(std::string(e.what()) ==
          "covariance: expected 3 rows of 3 entries, one per parameter of model duffing");
  }

  TEST_CASE("the chosen skip is where a linear oscillator's transient falls to 1%") {
    // c = 0.5, m = 1: the envelope decays as exp(-c t / 2), to 1% after 2 ln(100) / c s.
    const Model model = model_file("duffing.mom");
    SimulationOptions options = duffing_options(model, 20000);
    options.parameters = {{"eps", momentid::ParameterValue::exact("0")}};
    const Recorder recorder = simulated(model, options);
    const MemoryRecord record(model, recorder, {"y", "v", "x"}, "zoh");
    const ValidateResult result =
        validate(model, record.source(), with_parameters(model, {"eps=0"}));
    const double expected = 2 * std::log(100.0) / 0.5 / options.dt;
    // Every parameter by name: eps as given, c and k at their nominal values.
    CHECK(result.parameters.at("eps").value == 0);
    CHECK(result.parameters.at("eps").decimal == "0");
    CHECK(result.parameters.at("c").value == 0.5);
    CHECK(result.parameters.at("k").value == 4);
    MESSAGE("skip " << result.skip[0] << " rows, envelope " << expected);
    CHECK(std::abs(result.skip[0] / expected - 1) < 0.1);
    CHECK(result.skip_chosen);
  }

  TEST_CASE("a model barely damped for its record is said to depend on its start") {
    const Model model = model_file("duffing.mom");
    SimulationOptions options = duffing_options(model, 2000);
    const Recorder recorder = simulated(model, options);
    const MemoryRecord record(model, recorder, {"y", "v", "x"}, "zoh");
    const ValidateResult result =
        validate(model, record.source(), with_parameters(model, {"c=0.01"}));
    REQUIRE(result.warnings.size() >= 1);
    CHECK(result.warnings[0].find("still depends on its initial state") != std::string::npos);
    CHECK(result.skip[0] == 1000);
  }

  TEST_CASE("a model without inputs is compared over its whole free response") {
    const Model model = parse_model(
        "model decay\nstate y, v\nparam c = 0.4, k = 4\ny' = v\nv' = -c*v - k*y\n", "decay.mom");
    // y = exp(-a t) cos(w t), a = c/2, w = sqrt(k - a^2): the exact free decay from y = 1.
    const double a = 0.2, w = std::sqrt(4 - a * a), dt = 0.01;
    std::vector<double> t, y;
    for (int n = 0; n < 3000; ++n) {
      t.push_back(n * dt);
      y.push_back(std::exp(-a * t.back()) * std::cos(w * t.back()));
    }
    MemoryData data;
    data.columns = {{"t", t.data(), 1}, {"y", y.data(), 1}};
    data.rows = t.size();
    const ValidateResult result =
        validate(model, DataSource::memory(data), with_parameters(model, {}));
    CHECK(result.skip == std::vector<std::size_t>{0});
    CHECK(result.outputs[0].fit > 99.9);
    CHECK(result.outputs[0].cross.empty());
    CHECK(format_text(result).find("the model has no input") != std::string::npos);
  }

  TEST_CASE("an unstable model ends with the time, the run and the state") {
    const Model model = model_file("duffing.mom");
    const Recorder recorder = simulated(model, duffing_options(model, 5000));
    const MemoryRecord record(model, recorder, {"y", "v", "x"}, "zoh");
    const Error e = error_from<Error>(
        [&] { validate(model, record.source(), with_parameters(model, {"eps=-1"})); });
    const std::string what = e.what();
    CHECK(what.find("the simulation blew up: state '") == 0);
    CHECK(what.find(" at t = ") != std::string::npos);
    CHECK(what.find(" in run 1 with c=0.5, k=4, eps=-1") != std::string::npos);
  }

  TEST_CASE("estimates are read from identify's JSON, and bad files are located") {
    const Model model = model_file("duffing.mom");
    const auto write = [](const std::string& text) {
      const std::string path =
          (std::filesystem::temp_directory_path() / "momentid_validate_estimates.json").string();
      std::ofstream(path) << text;
      return path;
    };
    const std::string good = write(
        "{\"model\": \"duffing\", \"parameters\": {\"c\": {\"estimate\": 0.25}, \"k\": "
        "{\"estimate\": 3}, \"eps\": {\"estimate\": -1e-3}}}");
    const Estimates read = read_estimates(model, good);
    const momentid::ParameterValues& values = read.values;
    CHECK(read.covariance.empty());
    REQUIRE(values.size() == 3);
    CHECK(values.at("c").value == 0.25);
    CHECK(values.at("eps").value == -1e-3);
    CHECK(values.at("eps").decimal.empty());
    const DataError bad =
        error_from<DataError>([&] { read_estimates(model, write("{\n  \"model\": duffing\n}")); });
    CHECK(bad.location().line == 2);
    CHECK(bad.message().find("not JSON") == 0);
    const DataError missing = error_from<DataError>([&] {
      read_estimates(model, write("{\"parameters\": {\"c\": {\"estimate\": 1}, \"k\": "
                                  "{\"estimate\": 1}}}"));
    });
    CHECK(missing.message().find("no estimate of parameter 'eps'") == 0);
    // The covariance in declaration order, null as NaN; one of another shape is located.
    const std::string parameters =
        "{\"parameters\": {\"c\": {\"estimate\": 1}, \"k\": {\"estimate\": 1}, \"eps\": "
        "{\"estimate\": 1}},\n\"diagnostics\": {\"covariance\": ";
    const Estimates with =
        read_estimates(model, write(parameters + "[[1, 2, 3], [2, 5, 6], [3, 6, null]]}}"));
    REQUIRE(with.covariance.size() == 3);
    CHECK(with.covariance[1] == std::vector<double>{2, 5, 6});
    CHECK(std::isnan(with.covariance[2][2]));
    const DataError shape = error_from<DataError>(
        [&] { read_estimates(model, write(parameters + "[[1, 2], [2, 5]]}}")); });
    CHECK(shape.location().line == 2);
    CHECK(shape.message() == "\"covariance\": expected 3 rows of 3 entries, one per parameter");
  }
}

}  // namespace
}  // namespace momentid
