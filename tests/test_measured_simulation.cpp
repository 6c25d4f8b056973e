// Simulated data that look measured: measurement noise, a subset of channels, and a smooth
// band-limited input (the random-phase multisine) that the integrator evaluates exactly.

#include <doctest/doctest.h>

#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>

#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "momentid/writer.hpp"
#include "test_support.hpp"

namespace {

using momentid::InputSpec;
using momentid::Model;
using momentid::SimulationOptions;
using momentid::testing::model_file;
using momentid::testing::options_for;
using momentid::testing::Recorder;

double mean_of(const std::vector<double>& x) {
  double s = 0;
  for (double v : x) s += v;
  return s / static_cast<double>(x.size());
}

// Divided by the number of values, as the simulation measures a channel's spread.
double variance_of(const std::vector<double>& x) {
  const double m = mean_of(x);
  double s = 0;
  for (double v : x) s += (v - m) * (v - m);
  return s / static_cast<double>(x.size());
}

double correlation(const std::vector<double>& a, const std::vector<double>& b, std::size_t lag) {
  const double ma = mean_of(a), mb = mean_of(b);
  double s = 0;
  for (std::size_t i = 0; i + lag < a.size(); ++i) s += (a[i] - ma) * (b[i + lag] - mb);
  return s / static_cast<double>(a.size()) / std::sqrt(variance_of(a) * variance_of(b));
}

// X_k = sum_n x_n exp(-2 pi i k n / N).
std::complex<double> dft(const std::vector<double>& x, std::size_t k) {
  std::complex<double> sum = 0;
  const double n = static_cast<double>(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double angle = -2 * std::numbers::pi * static_cast<double>((k * i) % x.size()) / n;
    sum += x[i] * std::complex<double>(std::cos(angle), std::sin(angle));
  }
  return sum;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The lines of a CSV file that are neither metadata nor comments: the header, then the rows.
std::vector<std::string> table_lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') out.push_back(line);
  }
  return out;
}

std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string field; std::getline(in, field, ',');) out.push_back(field);
  return out;
}

// A scratch folder removed at the end of the test.
struct ScratchFolder {
  std::filesystem::path path;
  explicit ScratchFolder(const std::string& name)
      : path(std::filesystem::temp_directory_path() / name) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~ScratchFolder() { std::filesystem::remove_all(path); }
};

// Two inputs, for the per-input hold.
const char* const kTwoInputs = "state y\ninput u, w\nparam a = 1\ny' = -a*y + u + w\n";

}  // namespace

TEST_SUITE("measured simulation") {
  TEST_CASE("portable_cos_turns agrees with the C library to about an ulp") {
    // The reference in long double (64-bit mantissa on x86), after taking out the whole turns,
    // so that its own rounding is far below a double's ulp. Tolerance: 2 ulp of 1.
    const auto reference = [](double turns) {
      const long double r = static_cast<long double>(turns) - std::round(turns);
      return static_cast<double>(std::cos(2 * std::numbers::pi_v<long double> * r));
    };
    double worst = 0;
    for (int i = -20000; i <= 20000; ++i) {
      for (const double turns : {i / 9973.0, 1e6 + i / 9973.0, -3e9 + i / 9973.0}) {
        worst = std::max(worst, std::abs(momentid::portable_cos_turns(turns) - reference(turns)));
      }
    }
    CHECK(worst <= 2 * std::numeric_limits<double>::epsilon());
    CHECK(momentid::portable_cos_turns(0) == 1);
    CHECK(momentid::portable_cos_turns(0.5) == -1);
    CHECK(momentid::portable_cos_turns(-7) == 1);
    CHECK(momentid::portable_cos_turns(0x1p60) == 1);
    CHECK(momentid::portable_cos_turns(0x1p51 + 0.5) == -1);
  }

  TEST_CASE("a multisine's lines are consecutive odd harmonics of f0, the highest at f2") {
    // f1/f2 = 0.1 with 10 lines: m = 1 is the smallest with (2m+1)/(2m+19) >= 0.1, so
    // f0 = 5/21 and the lines are 3 f0 .. 21 f0 = 0.714 .. 5 Hz.
    const InputSpec spec = InputSpec::parse("multisine:f1=0.5,f2=5,lines=10", "--input");
    CHECK(spec.base_frequency() == 5.0 / 21);
    const std::vector<std::uint64_t> want{3, 5, 7, 9, 11, 13, 15, 17, 19, 21};
    CHECK(spec.harmonics() == want);
    // The lowest line may sit exactly at f1: f1 = 1, f2 = 3, 2 lines give f0 = 1, lines 1 and 3.
    const InputSpec edge = InputSpec::parse("multisine:f1=1,f2=3,lines=2", "--input");
    CHECK(edge.base_frequency() == 1);
    CHECK(edge.harmonics() == std::vector<std::uint64_t>{1, 3});
    // One line: a sine at f2.
    const InputSpec one = InputSpec::parse("multisine:f1=1,f2=3,lines=1", "--input");
    CHECK(one.harmonics() == std::vector<std::uint64_t>{1});
    CHECK(one.base_frequency() == 3);
  }

  TEST_CASE("multisine specifications are parsed, checked and written back") {
    const InputSpec spec =
        InputSpec::parse("multisine:lines=10,f2=5,f1=0.5,rms=2,mean=-1", "--input x");
    CHECK(spec.text() == "multisine:f1=0.5,f2=5,lines=10,rms=2,mean=-1");
    CHECK(InputSpec::parse(spec.text(), "--input x").text() == spec.text());
    CHECK(InputSpec::parse("multisine:f1=1e-3,f2=0.25,lines=3", "--input").text() ==
          "multisine:f1=0.001,f2=0.25,lines=3,rms=1,mean=0");
    CHECK_FALSE(spec.held());
    CHECK(InputSpec{}.held());
    const auto refused = [](const std::string& text, const std::string& message) {
      CHECK_THROWS_WITH_AS(InputSpec::parse(text, "--input x"), message.c_str(),
                           momentid::UsageError);
    };
    refused("multisine:f1=1,f2=2",
            "--input x: a multisine input needs f1, f2 and lines, e.g. "
            "multisine:f1=0.5,f2=5,lines=10");
    refused("multisine:f1=0,f2=2,lines=3", "--input x: f1 must be positive");
    refused("multisine:f1=1,f2=-2,lines=3", "--input x: f2 must be positive");
    refused("multisine:f1=2,f2=2,lines=3", "--input x: f1 must be below f2, found f1=2 and f2=2");
    refused("multisine:f1=1,f2=2,lines=0",
            "--input x: lines must be a whole number from 1 to 10000, found '0'");
    refused("multisine:f1=1,f2=2,lines=1.5",
            "--input x: lines must be a whole number from 1 to 10000, found '1.5'");
    refused("multisine:f1=1,f2=2,lines=3,rms=0", "--input x: rms must be positive");
    refused("multisine:f1=1,f2=2,lines=3,rms=x", "--input x: rms must be a number, found 'x'");
    refused("multisine:f1=1,f2=2,lines=3,sigma=1",
            "--input x: unknown setting 'sigma' for a multisine input");
    refused("multisine:f1=4.999999999999,f2=5,lines=10",
            "--input x: the band from f1=4.999999999999 to f2=5 is too narrow for 10 lines");
    // The Nyquist frequency needs the step: checked by validate, and so by the simulation.
    const InputSpec fast = InputSpec::parse("multisine:f1=1,f2=50,lines=3", "--input x");
    CHECK_NOTHROW(fast.validate("--input x", 0.0099));
    CHECK_THROWS_WITH_AS(fast.validate("--input x", 0.01),
                         "--input x: f2=50 must be below the Nyquist frequency 1/(2 dt) = 50",
                         momentid::UsageError);
    const Model model = model_file("kozin_4_1a.mom");
    SimulationOptions options = options_for(model, 10, 1);
    options.inputs = {fast};
    CHECK_THROWS_WITH_AS(options.validate(model),
                         "inputs x: f2=50 must be below the Nyquist frequency 1/(2 dt) = 50",
                         momentid::UsageError);
  }

  TEST_CASE("the multisine has the requested RMS over a period and energy only at its lines") {
    // f0 = 5/21 Hz: the period 4.2 s holds exactly N = 420 samples at dt = 0.01, so the DFT of
    // one period has no leakage: bin k is k f0, lines at bins 3, 5, ..., 21, amplitude A N/2
    // with A = rms sqrt(2/L). Tolerances: rounding only (the sums have 420 terms of size ~1).
    const InputSpec spec = InputSpec::parse("multisine:f1=0.5,f2=5,lines=10,rms=2,mean=0.5", "");
    const std::size_t n = 420;
    momentid::InputProcess input(spec, 0.01, 4, 0);
    std::vector<double> x(n);
    for (double& v : x) v = input.next();
    CHECK(std::abs(mean_of(x) - 0.5) < 1e-14);
    CHECK(std::abs(std::sqrt(variance_of(x)) - 2) < 1e-13);
    const double amplitude = 2 * std::sqrt(2.0 / 10);
    for (std::size_t k = 1; k <= n / 2; ++k) {
      const bool line = k % 2 == 1 && k >= 3 && k <= 21;
      const double magnitude = std::abs(dft(x, k)) / (amplitude * static_cast<double>(n) / 2);
      INFO("bin ", k, ": |X_k| / (A N/2) = ", magnitude);
      if (line) {
        CHECK(std::abs(magnitude - 1) < 1e-12);
      } else {
        CHECK(magnitude < 1e-12);
      }
    }
    // The phases differ from line to line (they are random, not a sweep).
    CHECK(std::abs(std::arg(dft(x, 3)) - std::arg(dft(x, 5))) > 1e-6);
  }

  TEST_CASE("a multisine's middle and end of step are its values at t + dt/2 and t + dt") {
    // The same phases (same seed and stream) on a clock of half the step: its values at even
    // counts are the coarse starts, at odd counts the coarse middles. Tolerance: rounding of the
    // phase (cycles per half step times the count), well below 1e-13.
    const InputSpec spec = InputSpec::parse("multisine:f1=0.5,f2=5,lines=10", "");
    momentid::InputProcess coarse(spec, 0.01, 2, 0), fine(spec, 0.005, 2, 0);
    double previous_end = 0;
    for (int step = 0; step < 500; ++step) {
      const double start = coarse.next();
      if (step > 0) CHECK(start == previous_end);  // exactly where the last step ended
      CHECK(std::abs(start - fine.next()) < 1e-13);
      CHECK(std::abs(coarse.middle() - fine.next()) < 1e-13);
      CHECK(std::abs(coarse.end() - fine.end()) < 1e-13);
      previous_end = coarse.end();
    }
  }

  TEST_CASE("RK4 with the exactly evaluated multisine converges at fourth order") {
    // y' = -y + x from y(0) = 0, x = sum_j Re(C_j exp(i w_j t)): the exact solution is
    // y = Re sum_j C_j (exp(i w_j t) - exp(-t)) / (1 + i w_j). The complex amplitudes C_j are
    // read off the DFT of one period of the written input (4.5 s, f0 = 2/9 Hz, lines at bins
    // 3, 5, 7, 9). Halving dt must divide the largest error over the period by 2^4 = 16; the
    // band [15, 17] allows for the higher-order terms (holding the input over each step would
    // make the error first order: a factor 2).
    const Model model = model_file("kozin_4_1a.mom");
    const InputSpec spec = InputSpec::parse("multisine:f1=0.5,f2=2,lines=4", "");
    REQUIRE(spec.base_frequency() == 2.0 / 9);
    std::vector<double> errors;
    for (const double h : {0.025, 0.0125, 0.00625}) {
      SimulationOptions options = options_for(model, static_cast<std::size_t>(4.5 / h + 0.5), 6);
      options.inputs = {spec};
      options.burn_in = 0;
      options.dt = h;
      Recorder rec(2);
      momentid::simulate(model, options, rec);
      const std::vector<double> y = rec.column(1), x = rec.column(2);
      const double n = static_cast<double>(x.size());
      double error = 0;
      for (std::size_t row = 0; row < x.size(); ++row) {
        const double t = static_cast<double>(row) * h;
        std::complex<double> exact = 0;
        for (std::size_t k : {3, 5, 7, 9}) {
          const std::complex<double> c = 2.0 * dft(x, k) / n;
          const double w = 2 * std::numbers::pi * static_cast<double>(k) * 2 / 9;
          const std::complex<double> rotation(std::cos(w * t), std::sin(w * t));
          exact += c * (rotation - std::exp(-t)) / std::complex<double>(1, w);
        }
        error = std::max(error, std::abs(y[row] - exact.real()));
      }
      errors.push_back(error);
    }
    INFO("errors ", errors[0], " ", errors[1], " ", errors[2]);
    CHECK(errors[0] < 1e-5);
    CHECK(errors[0] / errors[1] > 15);
    CHECK(errors[0] / errors[1] < 17);
    CHECK(errors[1] / errors[2] > 15);
    CHECK(errors[1] / errors[2] < 17);
  }

  TEST_CASE("separate runs draw new multisine phases, continued runs keep the clock running") {
    const Model model = model_file("kozin_4_1a.mom");
    SimulationOptions options = options_for(model, 300, 3);
    options.inputs = {InputSpec::parse("multisine:f1=0.5,f2=5,lines=10", "")};
    options.runs = 2;
    Recorder separate(2);
    momentid::simulate(model, options, separate);
    options.runs = 1;
    Recorder first(2);
    momentid::simulate(model, options, first);
    for (std::size_t row = 0; row < 300; ++row) {
      CHECK(separate.rows[row] == first.rows[row]);
      CHECK(separate.rows[row][2] != separate.rows[row + 300][2]);
    }
    // Continued runs are one long record cut in two: the same states and inputs row by row.
    options.runs = 2;
    options.continue_runs = true;
    Recorder continued(2);
    momentid::simulate(model, options, continued);
    options.runs = 1;
    options.samples = 600;
    Recorder whole(2);
    momentid::simulate(model, options, whole);
    for (std::size_t row = 0; row < 600; ++row) {
      CHECK(continued.rows[row][1] == whole.rows[row][1]);
      CHECK(continued.rows[row][2] == whole.rows[row][2]);
    }
  }

  TEST_CASE("input-hold is zoh for held inputs, sample for multisines and mixed for both") {
    const Model model = momentid::parse_model(kTwoInputs, "two.mom");
    SimulationOptions options = options_for(model, 10, 1);
    const InputSpec smooth = InputSpec::parse("multisine:f1=0.5,f2=5,lines=10", "");
    CHECK(momentid::simulation_metadata(model, options).text() ==
          "# momentid: model=two dt=0.01 input-hold=zoh seed=1 samples=10 runs=1 burn-in=2000 "
          "continue=no\n"
          "# momentid: param.a=1\n"
          "# momentid: input.u=ma:K=10,w=0.1,sigma=1,mean=0\n"
          "# momentid: input.w=ma:K=10,w=0.1,sigma=1,mean=0\n");
    options.inputs = {smooth, smooth};
    CHECK(momentid::simulation_metadata(model, options).get("input-hold") == "sample");
    CHECK_FALSE(momentid::simulation_metadata(model, options).get("input-hold.u"));
    options.inputs = {smooth, InputSpec{}};
    CHECK(momentid::simulation_metadata(model, options).text() ==
          "# momentid: model=two dt=0.01 input-hold=mixed seed=1 samples=10 runs=1 burn-in=2000 "
          "continue=no\n"
          "# momentid: param.a=1\n"
          "# momentid: input.u=multisine:f1=0.5,f2=5,lines=10,rms=1,mean=0 "
          "input-hold.u=sample\n"
          "# momentid: input.w=ma:K=10,w=0.1,sigma=1,mean=0 input-hold.w=zoh\n");
  }

  TEST_CASE("noise has the requested deviation, is white and leaves the clean values alone") {
    // Duffing: noise on the state y and the input x, none on v. N = 100000 samples; the noise d
    // is noisy - clean. Tolerances, 4 standard errors each: a Gaussian sample variance has
    // relative standard error sqrt(2/N); a sample mean sigma/sqrt(N); a sample correlation of
    // independent white series 1/sqrt(N).
    const Model model = model_file("duffing.mom");
    const std::size_t n = 100000;
    SimulationOptions options = options_for(model, n, 21);
    Recorder clean(3);
    momentid::simulate(model, options, clean);
    options.noise = {{"y", 0.2}, {"x", 0.5}};
    Recorder noisy(3);
    momentid::simulate(model, options, noisy);

    const std::vector<double> sd = momentid::noise_standard_deviations(model, options);
    REQUIRE(sd.size() == 2);
    const double bound = 4 / std::sqrt(static_cast<double>(n));
    std::vector<std::vector<double>> noise;
    for (const auto& channel :
         {std::tuple{std::size_t{1}, 0.2, sd[0]}, std::tuple{std::size_t{3}, 0.5, sd[1]}}) {
      const std::size_t column = std::get<0>(channel);
      const double relative = std::get<1>(channel), absolute = std::get<2>(channel);
      const std::vector<double> c = clean.column(column), m = noisy.column(column);
      // The deviation recorded is the level times the clean channel's (population) deviation.
      const double want = relative * std::sqrt(variance_of(c));
      CHECK(std::abs(absolute - want) < 1e-12 * want);
      std::vector<double> d(n);
      for (std::size_t i = 0; i < n; ++i) d[i] = m[i] - c[i];
      INFO("column ", column, ": noise sd ", std::sqrt(variance_of(d)), ", wanted ", want);
      CHECK(std::abs(variance_of(d) - want * want) < 4 * std::sqrt(2.0 / n) * want * want);
      CHECK(std::abs(mean_of(d)) < bound * want);
      CHECK(std::abs(correlation(d, d, 1)) < bound);
      CHECK(std::abs(correlation(d, d, 2)) < bound);
      CHECK(std::abs(correlation(d, c, 0)) < bound);
      noise.push_back(std::move(d));
    }
    CHECK(std::abs(correlation(noise[0], noise[1], 0)) < bound);
    // The trajectory does not see the noise: v, which has none, is unchanged bit for bit.
    CHECK(noisy.column(2) == clean.column(2));
    // A level of 0 adds nothing at all.
    options.noise = {{"y", 0}};
    Recorder zero(3);
    momentid::simulate(model, options, zero);
    CHECK(zero.rows == clean.rows);
  }

  TEST_CASE("noisy files are the same byte for byte for a seed, and record the noise") {
    const Model model = model_file("duffing.mom");
    const ScratchFolder dir("momentid_test_noise");
    SimulationOptions options = options_for(model, 2000, 7);
    options.noise = {{"v", 0.1}};
    auto write = [&](const std::string& name) {
      momentid::simulate_to_file(model, options, (dir.path / name).string(),
                                 momentid::DataWriter::Format::kCsv);
      return read_file(dir.path / name);
    };
    const std::string a = write("a.csv"), b = write("b.csv");
    CHECK(a == b);
    const double sd = momentid::noise_standard_deviations(model, options)[0];
    const momentid::DataMetadata metadata = momentid::simulation_metadata(model, options, {sd});
    CHECK(a.rfind(metadata.text(), 0) == 0);  // the file starts with it
    CHECK(metadata.lines().back() ==
          momentid::DataMetadata::Line{{"noise.v", "0.1"},
                                       {"noise-sd.v", *metadata.get("noise-sd.v")}});
    CHECK(std::stod(*metadata.get("noise-sd.v")) == sd);
    options.seed = 8;
    CHECK(write("c.csv") != a);
  }

  TEST_CASE("observe writes exactly the channels asked for, in their order") {
    const Model model = model_file("duffing.mom");
    const ScratchFolder dir("momentid_test_observe");
    SimulationOptions options = options_for(model, 50, 2);
    options.runs = 2;
    momentid::simulate_to_file(model, options, (dir.path / "all.csv").string(),
                               momentid::DataWriter::Format::kCsv);
    options.observe = {"x", "y"};
    momentid::simulate_to_file(model, options, (dir.path / "some.csv").string(),
                               momentid::DataWriter::Format::kCsv);
    const std::string some = read_file(dir.path / "some.csv");
    CHECK(some.find("continue=no observe=x,y\n") != std::string::npos);
    const std::vector<std::string> all_lines = table_lines(read_file(dir.path / "all.csv"));
    const std::vector<std::string> some_lines = table_lines(some);
    REQUIRE(all_lines.size() == 101);
    REQUIRE(some_lines.size() == 101);
    CHECK(all_lines[0] == "t,y,v,x,run");
    CHECK(some_lines[0] == "t,x,y,run");
    for (std::size_t i = 1; i < all_lines.size(); ++i) {
      const std::vector<std::string> all = fields(all_lines[i]);
      CHECK(some_lines[i] == all[0] + "," + all[3] + "," + all[1] + "," + all[4]);
    }
    // One run: no run column.
    options.runs = 1;
    options.observe = {"v"};
    momentid::simulate_to_file(model, options, (dir.path / "one.csv").string(),
                               momentid::DataWriter::Format::kCsv);
    CHECK(table_lines(read_file(dir.path / "one.csv"))[0] == "t,v");
  }

  TEST_CASE("noise and observe name channels the model has, once each") {
    const Model model = model_file("duffing.mom");
    SimulationOptions options = options_for(model, 10, 1);
    const auto refused = [&](const std::string& message) {
      CHECK_THROWS_WITH_AS(options.validate(model), message.c_str(), momentid::UsageError);
    };
    options.noise = {{"z", 0.1}};
    refused("noise: 'z' is not a channel of model duffing (channels: y, v, x)");
    options.noise = {{"y", 0.1}, {"y", 0.2}};
    refused("noise: channel 'y' is given twice");
    options.noise = {{"y", -0.1}};
    refused("noise: the level of 'y' must be a finite number of at least 0, found -0.1");
    options.noise = {{"y", std::nan("")}};
    refused("noise: the level of 'y' must be a finite number of at least 0, found nan");
    options.noise = {{"v", 0.1}};
    options.observe = {"y", "x"};
    refused("noise: channel 'v' is not observed (observe y,x)");
    options.noise.clear();
    options.observe = {"y", "q"};
    refused("observe: 'q' is not a channel of model duffing (channels: y, v, x)");
    options.observe = {"x", "x"};
    refused("observe: channel 'x' is given twice");

    const auto levels = momentid::parse_noise({"y=0.05", "x=1e-2"});
    REQUIRE(levels.size() == 2);
    CHECK(levels[0].channel == "y");
    CHECK(levels[0].relative == 0.05);
    CHECK(levels[1].relative == 0.01);
    CHECK_THROWS_WITH_AS(momentid::parse_noise({"y"}), "noise: expected CHANNEL=LEVEL, found 'y'",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(momentid::parse_noise({"y=5%"}),
                         "noise: the level of 'y' must be a number, found '5%'",
                         momentid::UsageError);
  }
}
