// The switching integrator of abs(...) and sign(...) models: sticking, sliding off, and the
// channels a simulation of such a model writes and checks.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "test_support.hpp"

namespace {

using momentid::InputSpec;
using momentid::Model;
using momentid::parse_model;
using momentid::SimulationOptions;
using momentid::testing::Recorder;

// A mass with Coulomb friction f under a constant force `force`, from rest.
Model friction(double force) {
  return parse_model(
      "state y, v\ninput x\nparam c = 4, f = 120, k = 1024\ny' = v\n"
      "v' = -c*v - f*sign(v) - k*y + x + " +
          std::to_string(force) + "\n",
      "friction.mom");
}

SimulationOptions quiet(const Model& model, std::size_t samples) {
  SimulationOptions options;
  options.inputs.assign(1, InputSpec{});
  options.inputs[0] = InputSpec::parse("ma:K=10,w=0.1,sigma=0", "input");
  options.samples = samples;
  options.burn_in = 0;
  options.dt = 1.0 / 1024;
  return options;
}

}  // namespace

TEST_SUITE("switching") {
  TEST_CASE("a force below the friction leaves the mass stuck where it is") {
    const Model model = friction(100);
    Recorder rec(3);
    momentid::simulate(model, quiet(model, 2000), rec);
    for (const auto& row : rec.rows) {
      CHECK(row[1] == 0);
      CHECK(row[2] == 0);
    }
  }

  TEST_CASE("a force above the friction slides the mass to rest at (force - f) / k") {
    // From rest the mass moves off, overshoots and sticks within the band |force - k y| <= f;
    // the viscous damping brings it to rest, stuck, at the first stop inside the band.
    const Model model = friction(300);
    Recorder rec(3);
    momentid::simulate(model, quiet(model, 20000), rec);
    const std::vector<double> y = rec.column(1), v = rec.column(2);
    CHECK(v[1] > 0);
    CHECK(v.back() == 0);
    CHECK(std::abs(300 - 1024 * y.back()) <= 120 * (1 + 1e-12));
    // Once stuck it stays: the last thousand samples are one and the same position.
    CHECK(std::all_of(y.end() - 1000, y.end(), [&](double x) { return x == y.back(); }));
  }

  TEST_CASE("the samples and the step check of a sign model hold its channels, not the sign") {
    const Model model = friction(0);
    SimulationOptions options = quiet(model, 200);
    options.inputs[0] = InputSpec::parse("ma:K=10,w=0.1,sigma=800", "input");
    CHECK(momentid::observed_channels(model, options) == std::vector<std::size_t>{0, 1, 2});
    Recorder rec(3);
    momentid::StepCheck check(model, options, rec);
    momentid::simulate(model, options, check);
    // The jump of sign(v) is not a fast eigenvalue: the largest is the oscillator's, 32 rad/s.
    CHECK(check.largest() == doctest::Approx(32.0 / 1024).epsilon(0.1));
    options.observe = {"sign(v)"};
    const auto e =
        momentid::testing::error_from<momentid::UsageError>([&] { options.validate(model); });
    CHECK(std::string(e.what()).find("'sign(v)' is not a channel of model") != std::string::npos);
    CHECK(std::string(e.what()).find("(channels: y, v, x)") != std::string::npos);
  }

  TEST_CASE("sign of a held input follows the input from step to step") {
    // y' = -a y + sign(x) with x held over each step: y_{n+1} = s + (y_n - s) exp(-a h) for
    // s = sign(x_n) / a, exactly.
    const Model model =
        parse_model("state y\ninput x\nparam a = 2\ny' = -a*y + sign(x)\n", "held.mom");
    SimulationOptions options = quiet(model, 400);
    options.inputs[0] = InputSpec::parse("ma:K=10,w=0.1,sigma=1", "input");
    options.dt = 0.01;
    Recorder rec(2);
    momentid::simulate(model, options, rec);
    double worst = 0;
    for (std::size_t n = 0; n + 1 < rec.rows.size(); ++n) {
      const double x = rec.rows[n][2], s = (x > 0 ? 1.0 : x < 0 ? -1.0 : 0.0) / 2;
      const double exact = s + (rec.rows[n][1] - s) * std::exp(-2 * 0.01);
      worst = std::max(worst, std::abs(rec.rows[n + 1][1] - exact));
    }
    CHECK(worst < 1e-10);
  }

  TEST_CASE("abs(y) crossing zero keeps the energy of a conservative oscillator") {
    // y'' = -k |y| y from y = 1 at rest, replayed without force: the energy v^2 / 2 + k |y|^3 / 3
    // stays 4 / 3; each crossing of y = 0 is located, so that the step keeps its order there.
    const Model model =
        parse_model("state y, v\ninput x\nparam k = 4\ny' = v\nv' = -k*abs(y)*y + x\n", "abs.mom");
    const momentid::RecordSimulator sim(model, {}, {momentid::Interpolation::kHold}, 0.01, 1);
    const auto states = sim.run({std::vector<double>(5000, 0.0)}, {1.0, 0.0}, 0.0, 1, 5000);
    double worst = 0;
    for (std::size_t n = 0; n < 5000; ++n) {
      const double y = states[0][n], v = states[1][n];
      worst = std::max(worst, std::abs(v * v / 2 + 4 * std::abs(y) * y * y / 3 - 4.0 / 3));
    }
    // About 40 crossings in 50 s: unlocated, each would cost of the order of h^2.
    CHECK(worst < 1e-7);
  }

  TEST_CASE("two frictions over several runs: each run starts at rest, stuck where it should") {
    const Model model = parse_model(
        "state y1, v1, y2, v2\ninput x\nparam f1 = 30, f2 = 40, k = 100\n"
        "y1' = v1\nv1' = -k*y1 - k*(y1 - y2) - f1*sign(v1) - v1 + x\n"
        "y2' = v2\nv2' = -k*(y2 - y1) - f2*sign(v2) - v2\n",
        "two.mom");
    SimulationOptions options = quiet(model, 3000);
    options.inputs[0] = InputSpec::parse("ma:K=10,w=0.1,sigma=200", "input");
    options.runs = 3;
    options.burn_in = 100;
    Recorder rec(5);
    momentid::simulate(model, options, rec);
    // Both masses stick now and then (v exactly 0 for consecutive samples), in every run, and the
    // friction never drives a stuck mass: its position is held, to rounding, while it sticks.
    for (double run = 0; run < 3; ++run) {
      std::size_t stuck1 = 0, stuck2 = 0;
      for (std::size_t n = 0; n + 1 < rec.rows.size(); ++n) {
        const auto &a = rec.rows[n], &b = rec.rows[n + 1];
        if (a.back() != run || b.back() != run) continue;
        if (a[2] == 0 && b[2] == 0) {
          ++stuck1;
          CHECK(std::abs(a[1] - b[1]) < 1e-14);
        }
        if (a[4] == 0 && b[4] == 0) {
          ++stuck2;
          CHECK(std::abs(a[3] - b[3]) < 1e-14);
        }
      }
      CHECK(stuck1 > 0);
      CHECK(stuck2 > 0);
    }
  }

  TEST_CASE("a function of both states and inputs is refused with its place") {
    const Model model = parse_model(
        "state y, v\ninput x\nparam k = 1, f = 5\ny' = v\nv' = -k*y - f*sign(v - x)\n", "belt.mom");
    const auto e = momentid::testing::error_from<momentid::ModelError>([&] {
      Recorder rec(3);
      momentid::simulate(model, quiet(model, 10), rec);
    });
    const std::string text = e.what();
    CHECK(text.find("belt.mom:5:") != std::string::npos);
    CHECK(text.find("sign(v - x) mixes states and inputs") != std::string::npos);
  }
}
