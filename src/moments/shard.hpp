#pragma once
// One shard of a pass (moments_from_data): what every shard shares, and the sums that one
// shard's rows give, read with the rows around it that its moments need.

#include <atomic>
#include <cstddef>
#include <optional>
#include <vector>

#include "momentid/accumulator.hpp"
#include "momentid/data_pass.hpp"
#include "moments/lag_sums.hpp"

namespace momentid {

// Where the accumulator keeps each channel: the states and the channels computed from them
// (continuous between rows), then the inputs and those computed from them (held with them).
struct ChannelLayout {
  ChannelLayout(std::size_t read_states, std::size_t read_inputs,
                const std::vector<ComputedChannel>& computed);
  // The accumulator's column of each channel: the states, inputs, then computed ones.
  std::vector<std::size_t> column;
  std::size_t states = 0, inputs = 0;  // the accumulator's counts
};

// What every shard's pass shares.
struct PassSetup {
  std::vector<Moment> moments;         // over the accumulator's columns (ChannelLayout)
  std::size_t states = 0, inputs = 0;  // the channels read
  ChannelLayout layout;
  InputHold hold = InputHold::kSample;
  std::size_t batches = 0;  // per shard
  bool collapse = false;    // each shard one stretch (many shards)
  const DataOptions* options = nullptr;
};

// What the merge needs to know of each shard besides its sums: its time steps (each file's
// interval is checked against the first file's) and the rows it dropped.
struct ShardSummary {
  DataReader::Steps steps;
  std::optional<double> time_step;  // the reader's
  MissingSummary missing;
};

// The sums of one shard, or of the shards merged so far.
struct ShardState {
  MomentAccumulator moments;
  LagSums lags;
  std::size_t rows = 0, runs = 0;
  ShardSummary summary;
};

// Reads one shard: the rows before it only as history of its first run, its own rows, and the
// rows after it only to close its last intervals. `whole`: the shard is a whole file, which can
// tell how far it is read. Adds the rows read to `rows_done`, and sets `fraction` to the
// fraction of the file read.
ShardState read_shard(DataReader& reader, bool whole, const PassSetup& setup, bool pipelined,
                      std::atomic<std::size_t>& rows_done, std::atomic<double>& fraction);

}  // namespace momentid
