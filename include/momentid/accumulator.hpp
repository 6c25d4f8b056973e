#pragma once

#include <cstddef>
#include <vector>

#include "momentid/model.hpp"

namespace momentid {

// How the input channels were sampled (README, "Estimating moments").
//  kSample: every channel holds samples of a continuous signal at the same instants; a moment is
//           the trapezoidal time average of its product.
//  kZeroOrderHold: input row n is held over [t_n, t_{n+1}) (what simulators do); a product with
//           an input is averaged as u[n] * (g(y_n) + g(y_{n+1})) / 2.
enum class InputHold { kSample, kZeroOrderHold };

// Time averages of the moments E[monomial] from a time series, in one streaming pass, kept per
// contiguous stretch of the record so that their sampling covariance can be estimated from batch
// means. Each moment is computed from precomputed powers of the channels and averaged over the
// intervals between consecutive rows of one run, never across runs (see close_interval).
//
// Accumulators merge exactly: sums and interval counts add, so shards of a record (or runs) can
// be accumulated anywhere and combined.
//
// Example:
//   MomentAccumulator acc(moments, /*states=*/2, /*inputs=*/1, InputHold::kZeroOrderHold, 20);
//   acc.start_run();
//   acc.add(rows, n);  // n rows of y1, y2, x
//   MomentEstimates e = acc.estimates(20);
class MomentAccumulator {
 public:
  // `batches`: how many batches the estimates will be split into at most; the accumulator
  // keeps between 2 and 4 times as many stretches, so its memory does not grow with the record.
  MomentAccumulator(std::vector<Monomial> moments, std::size_t states, std::size_t inputs,
                    InputHold hold, std::size_t batches);

  // The next rows belong to a new run (a separate record).
  void start_run();
  // Adds `rows` consecutive rows of the current run, each states then inputs.
  void add(const double* rows, std::size_t count);
  // Closes the current run: call after the last rows, before reading the stretches.
  void finish();
  // Appends another accumulator's stretches after this one's (same moments and hold).
  void merge(const MomentAccumulator& other);

  std::size_t intervals() const { return intervals_; }
  const std::vector<Monomial>& moments() const { return moments_; }

  // Per stretch of the record: sums of the interval averages and the number of intervals.
  struct Stretch {
    std::vector<double> sums;
    std::size_t intervals = 0;
  };
  // The stretches so far, in record order, of equal length but the last (unless merged).
  const std::vector<Stretch>& stretches() const { return stretches_; }

 private:
  void finish_run();
  void close_interval(std::size_t n);
  void compact();

  std::vector<Monomial> moments_;
  std::size_t states_, inputs_;
  InputHold hold_;
  // Moment i's state factors are factors_[first_factor_[2i] .. first_factor_[2i+1]), its input
  // factors follow up to first_factor_[2i+2]; entries index the power table.
  std::vector<std::size_t> factors_, first_factor_;
  std::vector<std::size_t> held_, plain_;  // moments averaged with a held input, and the others
  std::vector<int> max_power_;
  std::vector<std::size_t> power_offset_;
  std::vector<double> powers_;
  // The state and input parts of every moment at the last four rows of the run (row mod 4).
  std::vector<double> state_ring_, input_ring_;
  std::size_t run_rows_ = 0;
  std::vector<Stretch> stretches_;
  std::size_t max_stretches_;
  std::size_t stretch_length_ = 1;  // intervals per stretch, doubled when there are too many
  std::size_t intervals_ = 0;
};

// Moment estimates with their sampling covariance from batch means.
struct MomentEstimates {
  std::vector<double> mean;                      // one per moment: the time average
  std::vector<std::vector<double>> batch_means;  // batches x moments
  std::size_t intervals = 0;
  // Covariance of `mean` from the spread of the batch means: S / B with S their sample
  // covariance (batches of equal length).
  std::vector<std::vector<double>> covariance() const;
};

// Groups the accumulator's stretches into `batches` contiguous batches (fewer if the record is
// short) and returns the overall means and the batch means.
MomentEstimates estimates(const MomentAccumulator& accumulator, std::size_t batches);

}  // namespace momentid
