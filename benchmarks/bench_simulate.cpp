// RK4 steps per second of `simulate` on the Duffing model, against a hand-written RK4 loop for
// the same equations and the same input samples in the same run.
//
// Usage: bench_simulate [steps=2000000] [repetitions=5]

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "timing.hpp"
#include "usage.hpp"

namespace {

// Keeps the last sample so that the work cannot be optimised away.
struct LastSample : momentid::SampleSink {
  double checksum = 0;
  void sample(double, const double* values, std::size_t) override { checksum += values[0]; }
};

// y' = v, v' = -c v - k y - eps y^3 + x, with the same held input as simulate().
double hand_written(std::size_t steps, double dt, std::uint64_t seed) {
  const double c = 0.5, k = 4, eps = 1;
  momentid::InputProcess input(momentid::InputSpec{}, dt, seed, 0);
  double y = 0, v = 0, checksum = 0;
  auto fy = [](double, double vv) { return vv; };
  auto fv = [&](double yy, double vv, double x) {
    return -c * vv - k * yy - eps * yy * yy * yy + x;
  };
  for (std::size_t s = 0; s < steps; ++s) {
    const double x = input.next();
    checksum += y;
    const double k1y = fy(y, v), k1v = fv(y, v, x);
    const double k2y = fy(y + 0.5 * dt * k1y, v + 0.5 * dt * k1v),
                 k2v = fv(y + 0.5 * dt * k1y, v + 0.5 * dt * k1v, x);
    const double k3y = fy(y + 0.5 * dt * k2y, v + 0.5 * dt * k2v),
                 k3v = fv(y + 0.5 * dt * k2y, v + 0.5 * dt * k2v, x);
    const double k4y = fy(y + dt * k3y, v + dt * k3v), k4v = fv(y + dt * k3y, v + dt * k3v, x);
    y += dt / 6 * (k1y + 2 * k2y + 2 * k3y + k4y);
    v += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }
  return checksum;
}

}  // namespace

int main(int argc, char** argv) {
  if (asked_for_help(argc, argv, "usage: bench_simulate [steps=2000000] [repetitions=5]")) return 0;
  const std::size_t steps = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 2000000;
  const int repetitions = argc > 2 ? std::atoi(argv[2]) : 5;
  const momentid::Model model = momentid::parse_model(R"(
state y, v
input x
param c = 0.5, k = 4, eps = 1
y' = v
v' = -c*v - k*y - eps*y^3 + x
)",
                                                      "duffing.mom");
  momentid::SimulationOptions options;
  options.inputs = {momentid::InputSpec{}};
  options.samples = steps;
  options.burn_in = 0;
  double a = 0, b = 0;
  const double library = median_seconds(repetitions, [&] {
    LastSample sink;
    momentid::simulate(model, options, sink);
    a = sink.checksum;
  });
  const double hand = median_seconds(repetitions, [&] { b = hand_written(steps, 0.01, 1); });
  std::printf("RK4 steps of the Duffing model, %zu steps, median of %d runs\n", steps, repetitions);
  std::printf("  momentid simulate (compiled model): %7.2f M steps/s\n", steps / library / 1e6);
  std::printf("  hand-written C++ loop:              %7.2f M steps/s\n", steps / hand / 1e6);
  std::printf("  ratio hand-written / momentid:      %7.2f\n", library / hand);
  std::printf("  sum of y, relative difference:      %9.2e (the two differ only in rounding)\n",
              std::abs(a - b) / std::abs(b));
  return 0;
}
