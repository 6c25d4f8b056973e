#pragma once
// A range of a pass's shards, read on threads and merged in record order; with several
// processes, each reads a range, and the ranges travel as bytes to be merged in rank order.

#include <cstddef>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "momentid/data_pass.hpp"
#include "moments/shard.hpp"

namespace momentid {

// What a process makes of a range of shards: their sums merged in record order, the summary of
// each, and the first error in record order with its shard (`error` is then set).
struct RangeResult {
  std::optional<ShardState> state;
  std::vector<ShardSummary> summaries;  // of the shards merged, from the range's first
  std::size_t first_error = std::numeric_limits<std::size_t>::max();
  std::exception_ptr error;
};

// What every shard of one pass shares, and how the pass reads.
struct Pass {
  const DataSource& source;
  const std::vector<DataSource::Shard>& shards;
  const ColumnRequest& request;
  const PassSetup& setup;
  std::size_t merged_batches;  // of the merged state: it never compacts its stretches
};

// Reads shards [begin, end) on the pass's threads; the first error in record order stops the
// shards after it from starting. Nothing throws out of it. `first_reader`: the reader of shard
// `begin` when it is open already.
RangeResult read_range(const Pass& pass, std::size_t begin, std::size_t end,
                       std::unique_ptr<DataReader> first_reader);

// A range's result as bytes for the other processes, and back (`channels` and `lags` as the
// pass's channel statistics).
std::vector<std::uint8_t> encode(const RangeResult& r);
RangeResult decode(const std::vector<std::uint8_t>& bytes, std::size_t channels, std::size_t lags);

// The ranges of all processes, merged in record order (each range's result, in rank order).
RangeResult merge_ranges(std::vector<RangeResult> ranges);

}  // namespace momentid
