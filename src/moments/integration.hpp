#pragma once
// Channels formed in the pass from a column of their derivative (DataOptions::Integration): a
// fourth-order Butterworth high-pass on every channel read, and the trapezoidal integrator on
// the formed ones, so that the filtered channels keep the linear relations of the raw ones.

#include <array>
#include <cstddef>
#include <vector>

#include "momentid/data_pass.hpp"

namespace momentid {

class IntegrationFilter {
 public:
  // `integration.integrals` per channel in the order the rows hold them.
  explicit IntegrationFilter(const DataOptions::Integration& integration);

  // The rows of each run that are dropped while the filter settles.
  std::size_t warm_up() const { return warm_up_; }
  // The variance of channel c's output for white noise of unit variance on its input (the sum of
  // the squares of its impulse response).
  double noise_gain(std::size_t c) const;

  void start_run();
  // Filters `count` rows of `values` (one row after another) in place and returns how many of
  // them are left, at the front: rows of the warm-up are dropped, and each row's output is the
  // previous row's (the integrator's correction looks one row ahead).
  std::size_t apply(double* values, std::size_t count);

 private:
  // y = b0 x + s1; s1 = b1 x - a1 y + s2; s2 = b2 x - a2 y.
  struct Section {
    double b0 = 0, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
  };
  struct Channel {
    std::array<Section, 2> sections;
    double correction = 0;  // c in y[n-1] - c (y[n] - 2 y[n-1] + y[n-2])
    std::array<double, 4> state{};
    std::array<double, 2> past{};  // the two previous outputs of the sections
  };
  double step(Channel& c, double x) const;

  std::vector<Channel> channels_;
  std::size_t warm_up_ = 0;
  std::size_t seen_ = 0;  // rows of the current run
};

}  // namespace momentid
