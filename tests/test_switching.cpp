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
  options.parameters = momentid::parameter_values(model, {});
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
}
