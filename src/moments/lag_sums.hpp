#pragma once
// The channel statistics of a pass: sums for the mean, variance and autocorrelations of every
// channel, and the sums of a few monomials of them over a sample of the rows (point sums),
// mergeable across shards.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/bytes.hpp"
#include "momentid/data_pass.hpp"

namespace momentid {

// Sums for the mean, variance and lagged products of every channel, over pairs within runs, and
// of the squares of its sixth differences (the noise estimate, data_pass.hpp).
// Values are summed less an offset, the first row's, so that a large mean does not cancel the
// variance away in sum(x^2)/n - mean^2. Sums of shards merge: the pairs a shard owns are those
// whose later row is its own, and their earlier rows may come from the rows before the shard
// (add_history).
class LagSums {
 public:
  // The rows sampled for the point sums taken together.
  static constexpr std::size_t kPointGroup = 256;
  // `points`: monomials of the channels, summed over a sample of the rows added (add_points).
  LagSums(std::size_t channels, std::size_t lags, const std::vector<Monomial>& points = {});

  void start_run() { filled_ = 0; }
  // Rows of the run before the shard, which only pair with the shard's own rows.
  void add_history(const double* rows, std::size_t count);
  // `count` rows (row-major), taken a channel at a time.
  void add(const double* rows, std::size_t count);

  // The sums, for another process (load()).
  void save(ByteWriter& out) const;
  static LagSums load(ByteReader& in, std::size_t channels, std::size_t lags);
  // Adds the sums of `other`, the shard after this one's rows.
  void merge(const LagSums& other);

  // `held`: the inputs are held over each sample (the noise estimate's form: data_pass.hpp).
  ChannelStatistics statistics(std::size_t c, bool held) const;
  // The means of the points' monomials over the rows sampled (NaN without any).
  std::vector<double> point_means() const;

 private:
  // Fills column_ with channel c: its history, then the block's values less `offset`; returns
  // the largest |value| of the block as read.
  double fill_column(std::size_t c, const double* rows, std::size_t count, double offset);
  // Keeps the column's last `reach_` values as channel c's history.
  void keep_history(std::size_t c);
  // Adds the rows sampled among `count` rows to the point sums.
  void add_points(const double* rows, std::size_t count);

  // reach_: the rows kept before each block, for the lags and the sixth difference.
  std::size_t channels_, lags_, reach_;
  // Per channel, the run's last `reach_` values less the offset, oldest first (the last
  // min(filled_, reach_) of them are rows of the run). The block at hand, one channel at a time:
  // its history, then its values less the offset.
  std::vector<double> history_, column_;
  std::vector<double> offset_, sum_, sum_squares_, products_;
  // Per channel: the sum of the squares of the sixth differences over the rows with six rows of
  // the run before them, `differenced_` of them.
  std::vector<double> differences_;
  // Per lag and channel: the sums of the later and of the earlier values of the pairs.
  std::vector<double> lead_, lagged_;
  std::vector<std::size_t> pairs_;
  // Per channel: the largest |value| and its row among the rows added (the first such row).
  std::vector<double> largest_;
  std::vector<std::size_t> largest_row_;
  std::size_t filled_ = 0, count_ = 0, differenced_ = 0;
  // The point sums: each monomial's among the distinct ones, the distinct ones' sums over the
  // rows sampled, how many, and the rows to pass before the next (none without monomials).
  // load() restores the index and the sums alone, to be merged and read.
  std::vector<std::size_t> point_index_;
  std::vector<double> point_sums_;
  std::size_t point_rows_ = 0, point_skip_ = 0;
  // The point sums of the shards merged after this one's rows, in record order: added up only
  // in point_means(), so that sums merged in any grouping (threads, processes) add alike.
  struct PointPart {
    std::size_t rows = 0;
    std::vector<double> sums;
  };
  std::vector<PointPart> point_parts_;
  // Of up to kPointGroup rows sampled at a time: their weights, and a column of each power of
  // each channel c from power_at_[c] (its power 0, unused) on; each distinct monomial k the
  // product of the powers factors_[point_factors_[k] .. point_factors_[k + 1]).
  std::vector<std::size_t> power_at_, point_channels_;  // the latter: those with powers
  std::vector<double> powers_, point_weights_;
  std::vector<std::uint32_t> factors_, point_factors_;
};

}  // namespace momentid
