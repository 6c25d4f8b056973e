#pragma once
// The channel statistics of a pass: sums for the mean, variance and autocorrelations of every
// channel, mergeable across shards.

#include <cstddef>
#include <vector>

#include "common/bytes.hpp"
#include "momentid/data_pass.hpp"

namespace momentid {

// Sums for the mean, variance and lagged products of every channel, over pairs within runs.
// Values are summed less an offset, the first row's, so that a large mean does not cancel the
// variance away in sum(x^2)/n - mean^2. Sums of shards merge: the pairs a shard owns are those
// whose later row is its own, and their earlier rows may come from the rows before the shard
// (add_history).
class LagSums {
 public:
  LagSums(std::size_t channels, std::size_t lags);

  void start_run() { filled_ = 0; }
  // Rows of the run before the shard, which only pair with the shard's own rows.
  void add_history(const double* rows, std::size_t count);
  void add(const double* rows, std::size_t count);

  // The sums, for another process (load()).
  void save(ByteWriter& out) const;
  static LagSums load(ByteReader& in, std::size_t channels, std::size_t lags);
  // Adds the sums of `other`, the shard after this one's rows.
  void merge(const LagSums& other);

  // `held`: the inputs are held over each sample (smooth_lag_zero).
  ChannelStatistics statistics(std::size_t c, bool held) const;

 private:
  void remember(const double* row);

  std::size_t channels_, lags_;
  // The previous `lags_` rows less the offset, newest first from head_, stored twice in a row so
  // that they are contiguous from any head; this row less the offset, once per lag.
  std::vector<double> history_, repeated_;
  std::vector<double> offset_, sum_, sum_squares_, products_;
  // Per lag and channel: the sums of the later and of the earlier values of the pairs.
  std::vector<double> lead_, lagged_;
  std::vector<std::size_t> pairs_;
  // Per channel: the largest |value| and its row among the rows added (the first such row).
  std::vector<double> largest_;
  std::vector<std::size_t> largest_row_;
  std::size_t head_ = 0, filled_ = 0, count_ = 0;
};

}  // namespace momentid
