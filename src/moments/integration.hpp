#pragma once
// Channels formed in the pass from a column of their derivative (DataOptions::Integration): a
// linear-phase high-pass on every channel read, with the magnitude of a fourth-order
// Butterworth filter, and on a formed channel the same divided by (i w)^r, its r-fold integral.
// The filtered channels keep the linear relations of the raw ones, and, as the filter delays
// every frequency alike, it adds no phase that the equations could read as damping.

#include <complex>
#include <cstddef>
#include <vector>

#include "momentid/data_pass.hpp"

namespace momentid {

class IntegrationFilter {
 public:
  // `integration.integrals` per channel in the order the rows hold them.
  explicit IntegrationFilter(const DataOptions::Integration& integration);

  // The rows at the start of each run that give no output: the filter's length less one.
  std::size_t warm_up() const { return taps_ - 1; }
  // The variance of channel c's output for white noise of unit variance on its input (the sum of
  // the squares of its taps).
  double noise_gain(std::size_t c) const;
  // Channel c's taps: its output is sum_j taps[j] input(t - j).
  const std::vector<double>& taps(std::size_t c) const { return taps_of_.at(c); }

  void start_run();
  // Takes `count` rows (one after another) and appends to `out` the filtered rows that are
  // complete, each the filtered channels at the time (length - 1)/2 rows before its last input.
  void push(const double* rows, std::size_t count, std::vector<double>& out);
  // Appends the filtered rows of the run's remaining inputs.
  void flush(std::vector<double>& out);

 private:
  void convolve(std::size_t fresh, std::vector<double>& out);

  std::size_t channels_ = 0;
  std::size_t taps_ = 0;                      // odd: the response is centred on its middle tap
  std::size_t size_ = 0;                      // of the FFTs: each gives size_ - taps_ + 1 rows
  std::vector<std::vector<double>> taps_of_;  // per channel
  std::vector<std::vector<std::complex<double>>> spectrum_;  // per channel, of its taps
  std::vector<double> input_;  // the run's rows not yet consumed, with taps_ - 1 before them
  std::size_t seen_ = 0;       // rows of the run taken
};

}  // namespace momentid
