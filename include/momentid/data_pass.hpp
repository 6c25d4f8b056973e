#pragma once

#include <optional>
#include <string>
#include <vector>

#include "momentid/accumulator.hpp"
#include "momentid/reader.hpp"
#include "momentid/record_options.hpp"

namespace momentid {

// Mean, variance and autocorrelations of one channel (pairs never span two runs).
// White noise of variance s2 on a channel that is smooth apart from it. For a channel of a
// smooth signal it is the mean square of the channel's sixth difference over
// kSixthDifferenceGain (the sum of the squares of its weights, C(12, 6)): the difference's weight
// on a signal's spectrum, (2 sin(w/2))^12 / 924, is 15 to 300 times smaller than the fourth
// difference's below a third of the sample rate, and the squares are summed over the rows as
// they come, where the same from the autocovariances at lags 0 .. 6 is a difference of sums
// taken over rows that differ at the record's ends: on a noise-free shaker record of an
// acceleration (2048 Hz, 5-150 Hz force) that way found a noise of 8e-5 of its variance, which
// a displacement formed from the acceleration took into its cubic term, moving the stiffness by
// 14 standard errors; the sixth difference found 2e-7. Under inputs held over each sample, the
// states' derivatives jump at the samples, and the autocorrelation's smooth part is
// a + b s^2 + c |s|^3 + d s^4: held_lag_zero extrapolates it to lag 0 through lags 1 .. 4, and 1
// minus that is the noise's share of the variance.
inline constexpr std::size_t kNoiseDifference = 6;
inline constexpr double kSixthDifferenceGain = 924;
// The sixth difference at p[0] (p[-6] .. p[0]).
inline double sixth_difference(const double* p) {
  return p[0] - 6 * p[-1] + 15 * p[-2] - 20 * p[-3] + 15 * p[-4] - 6 * p[-5] + p[-6];
}
double held_lag_zero(const std::vector<double>& autocorrelation);

struct ChannelStatistics {
  std::string name;
  bool is_input = false;
  double mean = 0;
  double variance = 0;
  // The largest |value| and its row, from 0, among the record's rows (every run, in order).
  double largest = 0;
  std::size_t largest_row = 0;
  std::vector<double> autocorrelation;  // lags 1..L
  // Samples until the autocorrelation first drops below 1/e (L + 1 if it never does).
  std::size_t correlation_time = 0;
  // The variance of white noise on the channel, in one of the forms above. Meaningful for a
  // channel that is smooth apart from the noise, such as a measured state.
  std::optional<double> noise_variance;
  // The noise's standard deviation as a fraction of the channel's (a negative estimate counts
  // as none); nullopt without an estimate or a variance.
  std::optional<double> noise_fraction() const;
};

// A channel computed row by row from the channels read: |p| or sign(p) (0 at 0) of a polynomial
// p in them, as a model's abs and sign terms need (VariableFunction), or p itself, a product of
// channels that a filter must see whole (DataOptions::Integration). Its argument holds states
// alone or inputs alone, so that it is continuous or held as they are. Moments name the computed
// channels after the states and inputs, in order.
struct ComputedChannel {
  enum class Kind { kAbs, kSign, kPolynomial };
  Kind kind = Kind::kAbs;
  std::vector<std::pair<double, Monomial>> argument;  // over the states, then the inputs
};

// How one pass reads a record and what it estimates.
struct DataOptions {
  // The record's columns, sample interval, layout and input hold, and the pass's threads and
  // shards (every field is used).
  RecordOptions record;
  // How products with a held input are integrated over an interval.
  HeldRule held_rule = HeldRule::kCubic;
  // Contiguous batches of the record for the moments' sampling covariance; 0: automatic, one per
  // kAutoBatchIntervals intervals, at least min_batches, and from kMinAutoBatches to
  // kMaxAutoBatches (long_run_covariance needs batches longer than the states' correlation time,
  // and enough of them for its degrees of freedom).
  std::size_t batches = 0;
  std::size_t min_batches = 0;
  static constexpr std::size_t kAutoBatchIntervals = 200, kMinAutoBatches = 100,
                               kMaxAutoBatches = 1000;
  std::size_t lags = 1;  // autocorrelations computed, per channel
  std::size_t min_rows = 2;
  // Pair input row n with state row n + input_shift (0: the same row).
  long input_shift = 0;
  // The moments of every `stride`-th row of each run, from row `phase` on (after the input
  // shift), at a sample interval `stride` times the data's: the record sampled more coarsely, for
  // the sampling bias. The channel statistics still see every row.
  std::size_t stride = 1, phase = 0;
  // Columns that hold time derivatives of states (Model::measured_derivatives()): channels after
  // the inputs in the moments' numbering, read as the states are (never shifted or held).
  std::vector<std::string> derivatives;
  // Per channel (states, inputs, then derivatives): a value subtracted from every sample as it is
  // read, such as the channel's mean; empty: none.
  std::vector<double> offsets;
  // Channels computed from the others, after the offsets are subtracted.
  std::vector<ComputedChannel> computed;
  // Monomials of the channels read (states, inputs, then derivatives) whose means are wanted to a
  // few digits only (the variances behind the errors the record's ends leave): taken from a
  // sample of the rows each shard owns, every row at first, thinning as its rows grow to every
  // 32nd (DataMoments::point_means), without their cost at every row of a long record.
  std::vector<Monomial> point_moments;

  // Channels formed from a column of their derivative (identify's --integrate): every channel
  // goes through a linear-phase high-pass with the magnitude of a fourth-order Butterworth
  // filter of corner `corner` (Hz, at the sample interval `dt`), and a formed channel, read from
  // its derivative's column, through the same divided by (i w)^integrals[c] (1 or 2), its
  // integral, so that the filtered channels keep the linear relations of the raw ones. A computed
  // channel of channels filtered alone (no integral) is computed from the raw rows and filtered
  // with them, as the equations filtered whole hold it; one of a formed channel, from the
  // filtered rows. Each file is read whole; the first rows of each run, the filter's length,
  // give no rows.
  struct Integration {
    double corner = 0;
    double dt = 0;
    std::vector<int> integrals;  // per channel: states, inputs, derivatives (0: filtered alone)
  };
  std::optional<Integration> integration;
};

// What one pass over a data file yields.
struct DataMoments {
  MomentEstimates estimates;                // for the requested moments, in their order
  std::vector<ChannelStatistics> channels;  // the states, inputs, then derivatives
  DataMetadata metadata;
  InputHold hold = InputHold::kSample;
  std::optional<double> time_step;
  std::size_t rows = 0;
  std::size_t runs = 0;
  MissingSummary missing;  // rows dropped for missing values
  // The means of DataOptions::point_moments over the rows sampled, in their order.
  std::vector<double> point_means;

  // The statistics of the channel named `name`, or nullptr when the pass read none.
  const ChannelStatistics* channel(const std::string& name) const;
};

// Reads `source` once, streaming (memory does not grow with a file), and estimates `moments`
// over the model's variables (states, inputs, derivatives, then computed channels), with the
// channels' statistics. Throws
// DataError for bad data (the first problem in record order) and Error if a file cannot be read.
//
// The source is cut into shards (DataSource::shards; whole files with an input shift or a
// missing-value rule other than kError), each read with the rows around it that its moments
// need, and their states are merged in record order. The cut depends on the files' sizes only,
// so the result does not depend on the number of threads: it is the same to the last bit. With
// fewer shards than threads, each shard is read on one thread while its moments are accumulated
// on another.
DataMoments moments_from_data(const DataSource& source, const std::vector<std::string>& states,
                              const std::vector<std::string>& inputs,
                              const std::vector<Monomial>& moments, const DataOptions& options);
// The same for moments that may be lagged, over the channels `states` then `inputs` in order.
DataMoments moments_from_data(const DataSource& source, const std::vector<std::string>& states,
                              const std::vector<std::string>& inputs, std::vector<Moment> moments,
                              const DataOptions& options);

}  // namespace momentid

namespace momentid {

// Warnings about the data for the moment method: rows dropped for missing values (and, with
// MissingValues::kDropRow, neighbours joined across them), an input that is nearly white (lag-1
// autocorrelation below 0.5; the method needs a smooth input) and sampling too coarse for the
// dynamics (a state's lag-1 autocorrelation below 0.9: the trapezoidal averages of products
// with derivatives are then biased).
std::vector<std::string> data_warnings(const DataMoments& data);
// The warning for rows dropped for missing values (MissingSummary::rows > 0).
std::string missing_warning(const MissingSummary& missing);
// A value that decides a channel's moments: one that carries more than half of the channel's
// sum of squares over a record of at least kOutlierRows rows (a spike, a dropout marker, a unit
// error), or whose square is beyond doubles, named with its row and column; nullopt when no
// channel has one.
std::optional<std::string> outlier_warning(const DataMoments& data);
inline constexpr std::size_t kOutlierRows = 20;

}  // namespace momentid
