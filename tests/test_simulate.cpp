#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "momentid/writer.hpp"
#include "test_support.hpp"

namespace {

using momentid::testing::model_file;

using momentid::InputSpec;
using momentid::Model;
using momentid::SimulationOptions;
using momentid::testing::options_for;
using momentid::testing::Recorder;

// Mean of the samples and its standard error from the spread of `batches` batch means.
struct MeanWithError {
  double mean = 0, error = 0;
};
MeanWithError batch_mean(const std::vector<double>& x, int batches) {
  const std::size_t size = x.size() / static_cast<std::size_t>(batches);
  std::vector<double> means(static_cast<std::size_t>(batches), 0.0);
  for (int b = 0; b < batches; ++b) {
    for (std::size_t i = 0; i < size; ++i) means[b] += x[b * size + i];
    means[b] /= static_cast<double>(size);
  }
  MeanWithError out;
  for (double m : means) out.mean += m / batches;
  double ss = 0;
  for (double m : means) ss += (m - out.mean) * (m - out.mean);
  out.error = std::sqrt(ss / (batches - 1) / batches);
  return out;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_SUITE("simulate") {
  TEST_CASE("the oscillator's variances match the exact values for the moving-average input") {
    // System (4.1b): y1' = y2, y2' = -4 y2 - 16 y1 + x. The simulation is the RK4 map
    // y_{n+1} = F y_n + G x_n exactly, with x_n = sum_i w v_{n-i}; augmenting the state with the
    // last K-1 noise values gives a linear recursion whose stationary covariance P solves
    // P = A P A^T + B B^T. Its y-block is what the sample moments estimate.
    const Model model = model_file("kozin_4_1b.mom");
    const double h = 0.01;
    const int k = 10;
    Eigen::Matrix2d a;
    a << 0, 1, -16, -4;
    const Eigen::Matrix2d ha = h * a;
    const Eigen::Matrix2d identity = Eigen::Matrix2d::Identity();
    const Eigen::Matrix2d f =
        identity + ha + ha * ha / 2 + ha * ha * ha / 6 + ha * ha * ha * ha / 24;
    const Eigen::Vector2d g =
        h * (identity + ha / 2 + ha * ha / 6 + ha * ha * ha / 24) * Eigen::Vector2d(0, 1);
    const int dim = 2 + (k - 1);  // y1, y2, v_{n-1} .. v_{n-K+1}
    Eigen::MatrixXd big = Eigen::MatrixXd::Zero(dim, dim);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(dim);
    big.topLeftCorner(2, 2) = f;
    for (int i = 1; i < k; ++i) big.block(0, 1 + i, 2, 1) = 0.1 * g;  // w * v_{n-i}
    b.head(2) = 0.1 * g;                                              // w * v_n
    b(2) = 1;                                                         // v_n becomes v_{n-1}
    for (int i = 3; i < dim; ++i) big(i, i - 1) = 1;                  // shift the others
    Eigen::MatrixXd p = b * b.transpose(), power = big;
    for (int i = 0; i < 40; ++i) {  // doubling: P = sum_j A^j B B^T (A^T)^j
      p += power * p * power.transpose();
      power = power * power;
    }
    const double exact_y1 = p(0, 0), exact_y2 = p(1, 1), exact_y12 = p(0, 1);

    Recorder rec(3);
    momentid::simulate(model, options_for(model, 400000, 11), rec);
    std::vector<double> y1y1, y2y2, y1y2, xx;
    for (const auto& r : rec.rows) {
      y1y1.push_back(r[1] * r[1]);
      y2y2.push_back(r[2] * r[2]);
      y1y2.push_back(r[1] * r[2]);
      xx.push_back(r[3] * r[3]);
    }
    // 40 batches of 10^4 samples: far longer than the response's correlation time (~50
    // samples), so the batch means are nearly independent. Tolerance: 4 standard errors.
    for (const auto& moment :
         {std::tuple{"E[y1^2]", &y1y1, exact_y1}, std::tuple{"E[y2^2]", &y2y2, exact_y2},
          std::tuple{"E[y1*y2]", &y1y2, exact_y12}, std::tuple{"E[x^2]", &xx, 0.1}}) {
      const char* name = std::get<0>(moment);
      const double exact = std::get<2>(moment);
      const MeanWithError m = batch_mean(*std::get<1>(moment), 40);
      INFO(name, ": sample ", m.mean, " +- ", m.error, ", exact ", exact);
      CHECK(std::abs(m.mean - exact) < 4 * m.error);
      CHECK(m.error < 0.05 * std::abs(exact) + 1e-4);  // the test has power
    }
  }

  TEST_CASE("the moving-average input has the triangular autocorrelation of equal weights") {
    const std::size_t n = 200000;
    momentid::InputProcess input(InputSpec{}, 0.01, 3, 0);
    std::vector<double> x(n);
    for (double& v : x) v = input.next();
    double mean = 0;
    for (double v : x) mean += v / n;
    auto covariance = [&](std::size_t lag) {
      double s = 0;
      for (std::size_t i = 0; i + lag < n; ++i) s += (x[i] - mean) * (x[i + lag] - mean);
      return s / static_cast<double>(n - lag);
    };
    const double c0 = covariance(0);
    CHECK(std::abs(c0 - 0.1) < 4 * 0.1 * std::sqrt(2.0 * 10 / n) * 2);
    // Bartlett's standard error of a sample autocorrelation: sqrt((1 + 2 sum rho_j^2) / n).
    double sum_rho2 = 0;
    for (int j = 1; j < 10; ++j) sum_rho2 += std::pow((10.0 - j) / 10.0, 2);
    const double error = std::sqrt((1 + 2 * sum_rho2) / static_cast<double>(n));
    for (std::size_t lag = 1; lag <= 12; ++lag) {
      const double expected = lag < 10 ? (10.0 - static_cast<double>(lag)) / 10.0 : 0.0;
      const double rho = covariance(lag) / c0;
      INFO("lag ", lag, ": ", rho, " expected ", expected);
      CHECK(std::abs(rho - expected) < 4 * error);
    }
  }

  TEST_CASE("the same seed gives a byte-identical file, another seed does not") {
    const Model model = model_file("duffing.mom");
    const auto dir = std::filesystem::temp_directory_path() / "momentid_test_simulate";
    std::filesystem::create_directories(dir);
    auto write = [&](const std::string& name, std::uint64_t seed) {
      momentid::simulate_to_file(model, options_for(model, 5000, seed), (dir / name).string(),
                                 momentid::DataWriter::Format::kCsv);
      return read_file(dir / name);
    };
    const std::string a = write("a.csv", 7), b = write("b.csv", 7), c = write("c.csv", 8);
    CHECK(a == b);
    CHECK(a != c);
    CHECK(a.size() > 5000 * 20);
    std::filesystem::remove_all(dir);
  }

  TEST_CASE("the random numbers are the same on every machine") {
    // Pinned values: xoshiro256** from splitmix64, the polar method with portable_log. A change
    // here changes every simulated file.
    momentid::PortableRandom random(1, 0);
    CHECK(random.next() == 0xbaa24e21d05c2935ULL);
    const double z1 = random.normal(), z2 = random.normal();
    CHECK(z1 == -0.94609887012920613);
    CHECK(z2 == -0.0098117205003042125);
  }

  TEST_CASE("portable_log and portable_exp agree with the C library to about an ulp") {
    for (double x :
         {1e-300, 1e-10, 0.1, 0.5, 0.70710678, 0.9999999, 1.0, 1.5, 2.0, 10.0, 1e10, 1e300}) {
      CHECK(std::abs(momentid::portable_log(x) - std::log(x)) <=
            4e-16 * std::max(1.0, std::abs(std::log(x))));
    }
    for (double x : {-700.0, -50.0, -1.0, -1e-5, 0.0, 1e-5, 0.5, 1.0, 10.0, 300.0, 700.0}) {
      CHECK(std::abs(momentid::portable_exp(x) - std::exp(x)) <= 4e-16 * std::exp(x));
    }
  }

  TEST_CASE("a parameter in front of a derivative is solved for exactly") {
    // a*y2' + b*y2 + c*y1 = x with a = 2, b = 8, c = 32 is system (4.1b) scaled by 2 (x/2).
    const Model scaled = model_file("kozin_example2.mom");
    const momentid::CompiledModel f(scaled, {2, 8, 32});
    const double y[2] = {0.3, -0.7}, u[1] = {0.5};
    double rate[2];
    REQUIRE(f.derivative(y, u, rate));
    CHECK(rate[0] == -0.7);
    CHECK(rate[1] == doctest::Approx((-8 * -0.7 - 32 * 0.3 + 0.5) / 2).epsilon(1e-15));
  }

  TEST_CASE("a state-dependent coefficient of a derivative is solved at each evaluation") {
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam a\ny' = v\n(1 + y^2)*v' = -a*v - y + x\n", "m.mom");
    const momentid::CompiledModel f(model, {3});
    const double y[2] = {2, 0.5}, u[1] = {1};
    double rate[2];
    REQUIRE(f.derivative(y, u, rate));
    CHECK(rate[0] == 0.5);
    CHECK(rate[1] == doctest::Approx((-3 * 0.5 - 2 + 1) / 5.0).epsilon(1e-15));
  }

  TEST_CASE("a measured derivative column holds the state's rate at each sample") {
    const Model model = model_file("duffing_accelerometer.mom");
    SimulationOptions options = options_for(model, 500, 3);
    options.inputs[0] = InputSpec::parse("multisine:f1=0.05,f2=2,lines=40", "--input");
    Recorder record(4);  // y, v, x, a
    momentid::simulate(model, options, record);
    REQUIRE(record.rows.size() == 500);
    for (const auto& row : record.rows) {
      const double y = row[1], v = row[2], x = row[3], a = row[4];
      CHECK(a == doctest::Approx(-0.5 * v - 4 * y - y * y * y + x).epsilon(1e-12));
    }
    // A held input would make it jump at every sample.
    options.inputs[0] = InputSpec{};
    CHECK_THROWS_WITH_AS(momentid::simulate(model, options, record),
                         "inputs: the measured column 'a' (v') would jump at every sample of the "
                         "held "
                         "input x: give x a smooth process (x=multisine:f1=F1,f2=F2,lines=L) or "
                         "leave the column out (observe y,v,x)",
                         momentid::UsageError);
  }

  TEST_CASE("runs are numbered and, with continue, start where the previous one ended") {
    const Model model = model_file("kozin_4_1a.mom");
    SimulationOptions options = options_for(model, 100, 5);
    options.runs = 3;
    Recorder separate(2);
    momentid::simulate(model, options, separate);
    REQUIRE(separate.rows.size() == 300);
    CHECK(separate.rows[99][3] == 0);
    CHECK(separate.rows[100][3] == 1);
    CHECK(separate.rows[100][0] == 0);  // time restarts with each run
    CHECK(separate.rows[299][3] == 2);

    options.continue_runs = true;
    Recorder continued(2);
    momentid::simulate(model, options, continued);
    // y(t + h) from the last row of run 1 by the same RK4 step: y' = -y + x, x held.
    const double y = continued.rows[99][1], x = continued.rows[99][2], h = 0.01;
    const double k1 = -y + x, k2 = -(y + h / 2 * k1) + x, k3 = -(y + h / 2 * k2) + x,
                 k4 = -(y + h * k3) + x;
    CHECK(continued.rows[100][1] == doctest::Approx(y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)));
  }

  TEST_CASE("a state that blows up stops the simulation with the state, time and parameters") {
    const Model model =
        momentid::parse_model("state y\ninput x\nparam a = 20\ny' = a*y + x\n", "unstable.mom");
    SimulationOptions options = options_for(model, 100000, 1);
    options.burn_in = 0;
    Recorder rec(2);
    try {
      momentid::simulate(model, options, rec);
      FAIL("no error");
    } catch (const momentid::Error& e) {
      CHECK(std::string(e.what()) ==
            "the simulation blew up: state 'y' reached -1.1146462861365183e+100 at t = 11.74 in "
            "run 1 with a=20: the model is unstable for these values, or the step dt is too "
            "large");
    }
  }

  TEST_CASE("parameter values: nominal values, --set overrides, missing values are errors") {
    const Model model =
        momentid::parse_model("state y\ninput x\nparam a = 1, b\ny' = -a*y - b*y^3 + x\n", "m.mom");
    const auto values_of = [&](const std::vector<std::string>& assignments) {
      return momentid::parameter_vector(model,
                                        momentid::parse_parameter_values(model, assignments));
    };
    const auto values = values_of({"b=-2.5e-1", "a=+3"});
    CHECK(values[0] == 3);
    CHECK(values[1] == GiNaC::numeric(-1, 4));
    try {
      values_of({});
      FAIL("no error");
    } catch (const momentid::ModelError& e) {
      CHECK(
          std::string(e.what()) ==
          "m.mom:3:14: parameter 'b' has no value: give a nominal value in the model or parameters "
          "b=VALUE");
    }
    CHECK_THROWS_WITH_AS(values_of({"c=1"}),
                         "parameters: 'c' is not a parameter of model m (parameters: a, b)",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(values_of({"a=1x"}),
                         "parameters: the value of 'a' must be a number, found '1x'",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(values_of({"a"}), "parameters: expected NAME=VALUE, found 'a'",
                         momentid::UsageError);
  }

  TEST_CASE("input specifications are parsed, checked and written back") {
    CHECK(InputSpec::parse("ma:K=5,w=0.2,sigma=2", "--input").text() ==
          "ma:K=5,w=0.2,sigma=2,mean=0");
    CHECK(InputSpec::parse("ma:weights=[0.25,0.5,0.25],mean=1", "--input").text() ==
          "ma:weights=[0.25,0.5,0.25],sigma=1,mean=1");
    CHECK(InputSpec::parse("ou:tau=0.5", "--input").text() == "ou:tau=0.5,sigma=1,mean=0");
    CHECK(InputSpec::parse("white", "--input").text() == "white:sigma=1,mean=0");
    CHECK(InputSpec::parse("ma", "--input").text() == "ma:K=10,w=0.1,sigma=1,mean=0");
    CHECK_THROWS_WITH_AS(InputSpec::parse("pink", "--input x"),
                         "--input x: unknown input process 'pink' (expected ma:K=10,w=0.1, "
                         "ou:tau=T, white or multisine:f1=F1,f2=F2,lines=L)",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(InputSpec::parse("ou", "--input"),
                         "--input: an ou input needs its correlation time, e.g. ou:tau=0.5",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(InputSpec::parse("ma:K=2.5", "--input"),
                         "--input: K must be a whole number from 1 to 1000000, found '2.5'",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(InputSpec::parse("ma:K=3,weights=[1,2]", "--input"),
                         "--input: give either K and w, or weights, not both",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(InputSpec::parse("white:tau=1", "--input"),
                         "--input: unknown setting 'tau' for a white input", momentid::UsageError);
    CHECK_THROWS_WITH_AS(InputSpec::parse("ou:tau=-1", "--input"), "--input: tau must be positive",
                         momentid::UsageError);
  }

  TEST_CASE("simulation parameters are given by name, the others at their nominal values") {
    const Model duffing = model_file("duffing.mom");
    SimulationOptions options = options_for(duffing, 10, 3);
    options.parameters = {{"k", momentid::ParameterValue::exact("4.5")}, {"eps", 0.25}};
    CHECK(momentid::simulation_metadata(duffing, options).get("param.c") == "0.5");
    CHECK(momentid::simulation_metadata(duffing, options).get("param.k") == "4.5");
    CHECK(momentid::simulation_metadata(duffing, options).get("param.eps") == "0.25");
    options.parameters = {{"zz", 1.0}};
    CHECK_THROWS_WITH_AS(options.validate(duffing),
                         "parameters: 'zz' is not a parameter of model duffing (parameters: c, k, "
                         "eps)",
                         momentid::UsageError);
    const Model bare = momentid::parse_model("state y\nparam a\ny' = -a*y\n", "bare.mom");
    SimulationOptions none = options_for(bare, 10, 1);
    CHECK_THROWS_AS(none.validate(bare), momentid::ModelError);
    none.parameters = {{"a", 2.0}};
    Recorder rows(1);
    momentid::simulate(bare, none, rows);
    CHECK(rows.rows.size() == 10);
  }

  TEST_CASE("the step check finds the linear oscillator's eigenvalues and a hardening spring's") {
    // y'' + c y' + k y = x: eigenvalues -c/2 +- i sqrt(k - c^2/4), of modulus sqrt(k) = 2.
    const Model duffing = model_file("duffing.mom");
    for (const double dt : {0.2, 0.3}) {
      SimulationOptions options = options_for(duffing, 2000, 3);
      options.parameters = {{"eps", momentid::ParameterValue::exact("0")}};
      options.dt = dt;
      Recorder rows(3);
      momentid::StepCheck check(duffing, options, rows);
      momentid::simulate(duffing, options, check);
      CHECK(rows.rows.size() == 2000);  // every sample passed on
      // The central difference of a linear model is exact up to rounding.
      CHECK(check.largest() == doctest::Approx(2 * dt).epsilon(1e-8));
      CHECK(check.warning().has_value() == (2 * dt > momentid::StepCheck::kLimit));
    }
    SimulationOptions options = options_for(duffing, 2000, 3);
    options.dt = 0.3;
    Recorder rows(3);
    momentid::StepCheck check(duffing, options, rows);
    momentid::simulate(duffing, options, check);
    REQUIRE(check.warning());
    const std::string warning = *check.warning();
    CHECK(warning.starts_with("the step is coarse for the model's dynamics: linearised at t = "));
    CHECK(warning.ends_with(
        "; fourth-order Runge-Kutta is accurate for |lambda| dt well below 1 and unstable beyond "
        "2.8: use --dt 0.1 or smaller"));
    // eps y^3 stiffens the spring to k + 3 eps y^2 where |y| is large.
    CHECK(check.largest() > 2 * 0.3);
  }

  TEST_CASE("a moving average over T seconds has T/dt rounded equal weights, 1/K by default") {
    const InputSpec window = InputSpec::parse("ma:T=0.1,sigma=2", "--input");
    CHECK(window.text() == "ma:T=0.1,sigma=2,mean=0");
    CHECK(InputSpec::parse(window.text(), "--input").text() == window.text());
    CHECK(window.weights_at(0.01) == std::vector<double>(10, 0.1));
    CHECK(window.weights_at(0.03) == std::vector<double>(3, 1.0 / 3));  // 3.33 steps
    CHECK(window.weights_at(0.15) == std::vector<double>(1, 1.0));
    const InputSpec weighted = InputSpec::parse("ma:T=0.05,w=0.5", "--input");
    CHECK(weighted.text() == "ma:T=0.05,w=0.5,sigma=1,mean=0");
    CHECK(weighted.weights_at(0.01) == std::vector<double>(5, 0.5));
    // The same process as its count in samples: the same values.
    momentid::InputProcess by_time(window, 0.01, 4, 0);
    momentid::InputProcess by_count(InputSpec::parse("ma:K=10,w=0.1,sigma=2", "--input"), 0.01, 4,
                                    0);
    for (int n = 0; n < 100; ++n) REQUIRE(by_time.next() == by_count.next());
    CHECK_THROWS_WITH_AS(InputSpec::parse("ma:T=0.1,K=10", "--input"),
                         "--input: give the window either in seconds (T) or in samples (K or "
                         "weights), not both",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(InputSpec::parse("ma:T=0", "--input"),
                         "--input: T must be a positive number of seconds, found '0'",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(window.validate("--input x", 0.5),
                         "--input x: T=0.1 is shorter than half a step (dt = 0.5)",
                         momentid::UsageError);
    CHECK_THROWS_WITH_AS(window.validate("--input x", 1e-8),
                         "--input x: T=0.1 is longer than 1000000 steps (dt = 1e-08)",
                         momentid::UsageError);
  }

  TEST_CASE("the Ornstein-Uhlenbeck input has variance sigma^2 and correlation exp(-dt/tau)") {
    const std::size_t n = 400000;
    momentid::InputProcess input(InputSpec::parse("ou:tau=0.05,sigma=2", "--input"), 0.01, 9, 0);
    std::vector<double> x(n);
    for (double& v : x) v = input.next();
    std::vector<double> squares, products;
    for (std::size_t i = 0; i + 1 < n; ++i) {
      squares.push_back(x[i] * x[i]);
      products.push_back(x[i] * x[i + 1]);
    }
    const MeanWithError var = batch_mean(squares, 40), cov = batch_mean(products, 40);
    CHECK(std::abs(var.mean - 4) < 4 * var.error);
    CHECK(std::abs(cov.mean - 4 * std::exp(-0.2)) < 4 * cov.error);
  }
}
