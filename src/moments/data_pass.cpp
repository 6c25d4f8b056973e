#include "momentid/data_pass.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <stdexcept>

#include "common/cluster.hpp"
#include "data/array_writers.hpp"
#include "data/formats.hpp"
#include "data/text.hpp"
#include "momentid/algebra_lock.hpp"
#include "moments/range.hpp"

// The pass: cut the source into shards, read a range of them on this process's threads
// (range.cpp; each shard by shard.cpp), merge the ranges of the other processes
// (range_exchange.cpp), then check the record as a whole and make the estimates.

namespace momentid {
namespace {

using data::plural;

// How long a process of an MPI job waits for the others at least, before it ends the job as one
// of them has stopped (docs/robustness.md).
constexpr std::chrono::seconds kMinimumPatience(60);

// The largest lag of the moments, in rows.
std::size_t max_lag_of(const std::vector<Moment>& moments) {
  std::size_t out = 0;
  for (const Moment& m : moments) {
    for (const MomentFactor& f : m.factors()) out = std::max(out, static_cast<std::size_t>(f.lag));
  }
  return out;
}

// The order the channels are read in: states, derivatives, inputs, so that the pass takes the
// derivatives for states (continuous, never shifted), while moments number them after the
// inputs. `read[c]` is the read position of channel c in the moments' numbering (states,
// inputs, derivatives, computed).
struct ReadOrder {
  std::vector<std::size_t> read;
  std::size_t states = 0, inputs = 0;  // as read: the derivatives count among the states

  ReadOrder(std::size_t s, std::size_t i, std::size_t d, std::size_t computed)
      : read(s + i + d + computed), states(s + d), inputs(i) {
    for (std::size_t c = 0; c < read.size(); ++c) {
      read[c] = c < s ? c : c < s + i ? c + d : c < s + i + d ? c - i : c;
    }
  }
  Monomial monomial(const Monomial& m) const {
    Monomial out(m.size(), 0);
    for (std::size_t c = 0; c < m.size(); ++c) out[read[c]] = m[c];
    return out;
  }
  template <typename T>
  std::vector<T> values(const std::vector<T>& by_channel) const {
    std::vector<T> out(by_channel.size());
    for (std::size_t c = 0; c < by_channel.size(); ++c) out[read[c]] = by_channel[c];
    return out;
  }
};

ColumnRequest column_request(const std::vector<std::string>& states,
                             const std::vector<std::string>& inputs, const DataOptions& options,
                             bool several_files) {
  ColumnRequest request;
  request.names = states;
  request.names.insert(request.names.end(), options.derivatives.begin(), options.derivatives.end());
  request.names.insert(request.names.end(), inputs.begin(), inputs.end());
  request.rename = options.record.columns;
  // Several files: the minimum is the whole record's, checked at its end.
  request.min_rows = several_files ? 0 : options.min_rows;
  request.dt = options.record.dt;
  request.layout = options.record.layout;
  return request;
}

InputHold input_hold(const DataMetadata& metadata, const DataOptions& options) {
  if (options.record.hold) return *options.record.hold;
  return metadata.input_hold();
}

// A file's sample interval, from the steps of its shards (else from elsewhere: the metadata,
// --dt).
std::optional<double> file_step(const DataReader::Steps& steps, std::optional<double> other) {
  return steps.count > 0 ? std::optional(steps.sum / static_cast<double>(steps.count)) : other;
}

// Adds up the shards' missing rows into `out`, and checks that each file's interval is the first
// file's, in record order, up to the first shard that failed. Returns the first file's interval.
std::optional<double> check_file_intervals(const RangeResult& result,
                                           const std::vector<DataSource::Shard>& shards,
                                           const std::vector<std::string>& paths,
                                           DataMoments& out) {
  std::optional<double> first_step;
  DataReader::Steps file_steps;
  for (std::size_t k = 0; k < result.summaries.size(); ++k) {
    const ShardSummary& s = result.summaries[k];
    out.missing.add(s.missing);
    file_steps.count += s.steps.count;
    file_steps.sum += s.steps.sum;
    if (shards[k].index + 1 < shards[k].count) continue;
    const std::optional<double> step = file_step(file_steps, s.time_step);
    file_steps = {};
    if (shards[k].file == 0) {
      first_step = step;
    } else {
      data::check_file_interval(paths[shards[k].file], step, paths.front(), first_step);
    }
  }
  return first_step;
}

// The size of the regular file at `path` (-1 for anything else, or one that cannot be read,
// which is never opened: a pipe would block) and an FNV-1a hash of its first and last 4 kB: its
// header and metadata, and its last rows.
std::array<std::int64_t, 2> fingerprint(const std::string& path) {
  constexpr off_t kEnd = 4096;
  struct stat s {};
  if (::stat(path.c_str(), &s) != 0 || !S_ISREG(s.st_mode)) return {-1, 0};
  const data::File file(std::fopen(path.c_str(), "rb"));
  if (!file) return {-1, 0};
  data::ColumnHash hash;
  std::array<unsigned char, kEnd> buffer{};
  const auto add = [&](off_t from) {
    if (fseeko(file.get(), from, SEEK_SET) != 0) return;
    hash.add_bytes(buffer.data(), std::fread(buffer.data(), 1, buffer.size(), file.get()));
  };
  add(0);
  if (s.st_size > kEnd) add(s.st_size - kEnd);
  return {static_cast<std::int64_t>(s.st_size), static_cast<std::int64_t>(hash.value())};
}

// In an MPI job, throws on every process alike unless each sees the same files, each of the same
// size and with the same first and last 4 kB (a stale copy on one node would give it other rows,
// or fewer).
void check_same_files(const DataSource& source, const std::vector<std::string>& paths) {
  std::vector<std::int64_t> mine;
  for (const std::string& path : paths) {
    const std::array<std::int64_t, 2> f = fingerprint(path);
    mine.insert(mine.end(), f.begin(), f.end());
  }
  std::vector<std::uint8_t> bytes(mine.size() * sizeof(std::int64_t));
  std::memcpy(bytes.data(), mine.data(), bytes.size());
  const std::vector<std::vector<std::uint8_t>> all = cluster::all_gather(bytes, kMinimumPatience);
  for (std::size_t r = 1; r < all.size(); ++r) {
    if (all[r].size() != all[0].size()) {  // a pattern that matched other files
      throw Error(source.name() + ": the processes of the job see different files (" +
                  plural(all[0].size() / 16, "file") + " on process 0, " +
                  std::to_string(all[r].size() / 16) + " on process " + std::to_string(r) +
                  "): give every process the same files");
    }
  }
  // Value k (0 the size, 1 the hash) of file f on process r.
  const auto value = [&](std::size_t r, std::size_t f, std::size_t k) {
    std::int64_t v = 0;
    std::memcpy(&v, all[r].data() + (2 * f + k) * sizeof v, sizeof v);
    return v;
  };
  for (std::size_t f = 0; f < paths.size(); ++f) {
    const std::string name = paths.size() == 1 ? source.name() : paths[f];
    const std::string advice = "): give every process the same file";
    std::string sizes;
    bool same_size = true;
    for (std::size_t r = 0; r < all.size(); ++r) {
      const std::int64_t size = value(r, f, 0);
      sizes += (r ? ", " : "") + (size < 0 ? std::string("none") : std::to_string(size)) +
               " on process " + std::to_string(r);
      same_size = same_size && size == value(0, f, 0);
    }
    if (!same_size) {
      throw Error(name + ": the processes of the job see different files (bytes: " + sizes +
                  advice);
    }
    for (std::size_t r = 1; r < all.size(); ++r) {
      if (value(r, f, 1) != value(0, f, 1)) {
        throw Error(name + ": the processes of the job see different files (" +
                    std::to_string(value(0, f, 0)) + " bytes each, other contents on process " +
                    std::to_string(r) + " than on process 0" + advice);
      }
    }
  }
}

// Throws when a file of the record changed while it was read (DataSource::check_unchanged): in
// an MPI job (`shared`) on every process alike, with the message of the first that saw it.
void check_unchanged(const DataSource& source, bool shared) {
  std::string changed;
  try {
    source.check_unchanged();
  } catch (const Error& e) {
    changed = e.what();
  }
  if (shared) {
    for (const auto& said :
         cluster::all_gather({changed.begin(), changed.end()}, kMinimumPatience)) {
      if (!said.empty()) {
        changed.assign(said.begin(), said.end());
        break;
      }
    }
  }
  if (!changed.empty()) throw Error(changed);
}

// Throws when the record as a whole has too few rows, or no interval to average over.
void check_record(const DataSource& source, const ShardState& state, bool any_moments,
                  std::size_t shards, const DataOptions& options) {
  const std::vector<std::string> paths = source.paths();
  const bool several_files = paths.size() > 1;
  if (state.rows < options.min_rows && (several_files || shards > 1)) {
    throw DataError({paths.empty() ? source.name() : paths.back(), 1, 1, ""},
                    "the data have " + plural(state.rows, "row") +
                        (several_files ? " in " + plural(paths.size(), "file") : std::string()) +
                        "; at least " + std::to_string(options.min_rows) + " are needed");
  }
  const MomentAccumulator& accumulator = state.moments;
  if (accumulator.intervals() == 0 && any_moments && accumulator.max_lag() > 0) {
    throw Error(source.name() + ": no run has more than " +
                std::to_string(accumulator.max_lag() + 1) + " rows" +
                (options.input_shift != 0 ? " after the input shift" : std::string()) +
                ": the lagged moments reach " + std::to_string(accumulator.max_lag()) +
                " rows back and need at least one interval after that");
  }
  if (accumulator.intervals() == 0 && any_moments) {
    throw Error(source.name() + ": no run has two consecutive rows" +
                (options.input_shift != 0 ? " after the input shift" : std::string()) +
                ": the time averages need at least one interval");
  }
}

// Reads this process's range of the shards and, in an MPI job, merges every process's range.
// The first shard's reader, opened already for the metadata, is handed on (or its error).
RangeResult read_all(const Pass& pass, std::unique_ptr<DataReader> first,
                     std::exception_ptr open_error, std::size_t channels) {
  const DataOptions& options = *pass.setup.options;
  // With several processes (MPI), each reads a contiguous range of the shards.
  const bool shared = options.record.control.across_processes;
  const std::size_t ranks = shared ? static_cast<std::size_t>(cluster::size()) : 1;
  const std::size_t rank = shared ? static_cast<std::size_t>(cluster::rank()) : 0;
  const std::size_t begin = pass.shards.size() * rank / ranks;
  const std::size_t end = pass.shards.size() * (rank + 1) / ranks;
  using clock = std::chrono::steady_clock;
  const clock::time_point start = clock::now();
  RangeResult result;
  if (open_error) {
    result = read_range(pass, 0, 0, nullptr);
    result.first_error = 0;
    result.error = open_error;
  } else {
    result = read_range(pass, begin, end, begin == 0 ? std::move(first) : nullptr);
  }
  if (ranks > 1) {
    // The others read as much: a process that has not finished long after this one has stopped.
    const auto patience =
        std::max<std::chrono::steady_clock::duration>(kMinimumPatience, 4 * (clock::now() - start));
    std::vector<RangeResult> ranges;
    for (const std::vector<std::uint8_t>& bytes : cluster::all_gather(encode(result), patience)) {
      ranges.push_back(decode(bytes, channels, options.lags));
    }
    result = merge_ranges(std::move(ranges));
  }
  return result;
}

// `moments` over the accumulator's columns (ChannelLayout) rather than the channels. The
// columns of the states are theirs, so increments, which are of states, stay as they are.
std::vector<Moment> in_columns(std::vector<Moment> moments, const ReadOrder& order,
                               const ChannelLayout& layout) {
  for (Moment& m : moments) {
    if (m.is_increment()) continue;
    std::vector<MomentFactor> factors = m.factors();
    for (MomentFactor& f : factors) {
      const std::size_t read = order.read.at(static_cast<std::size_t>(f.channel));
      f.channel = static_cast<int>(layout.column.at(read));
    }
    m = Moment(std::move(factors));
  }
  return moments;
}

// The channels' statistics, named, in the moments' numbering (states, inputs, derivatives).
std::vector<ChannelStatistics> channel_statistics(const LagSums& sums,
                                                  const std::vector<std::string>& names,
                                                  const ReadOrder& order, bool held) {
  std::vector<ChannelStatistics> out;
  for (std::size_t c = 0; c < names.size(); ++c) {
    const std::size_t read = order.read[c];
    ChannelStatistics s = sums.statistics(read, held);
    s.name = names[read];
    s.is_input = read >= order.states;
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace

DataMoments moments_from_data(const DataSource& source, const std::vector<std::string>& states,
                              const std::vector<std::string>& inputs,
                              const std::vector<Monomial>& moments, const DataOptions& options) {
  std::vector<Moment> keys;
  for (const Monomial& m : moments) keys.push_back(Moment::from_monomial(m));
  return moments_from_data(source, states, inputs, std::move(keys), options);
}

DataMoments moments_from_data(const DataSource& source, const std::vector<std::string>& states,
                              const std::vector<std::string>& inputs, std::vector<Moment> keys,
                              const DataOptions& options) {
  const std::vector<std::string> paths = source.paths();
  const bool shared = options.record.control.across_processes && cluster::size() > 1;
  if (shared) check_same_files(source, paths);
  ColumnRequest request = column_request(states, inputs, options, paths.size() > 1);
  const std::size_t channels = request.names.size();
  if (!options.offsets.empty() && options.offsets.size() != channels) {
    throw std::invalid_argument("moments_from_data: one offset per channel needed");
  }
  const ReadOrder order(states.size(), inputs.size(), options.derivatives.size(),
                        options.computed.size());
  if (options.integration && options.integration->integrals.size() != channels) {
    throw std::invalid_argument("moments_from_data: one integral count per channel needed");
  }
  // The shards see the channels in the order read.
  DataOptions read_options = options;
  if (!options.offsets.empty()) read_options.offsets = order.values(options.offsets);
  for (ComputedChannel& c : read_options.computed) {
    for (auto& [coefficient, monomial] : c.argument) monomial = order.monomial(monomial);
  }
  for (Monomial& m : read_options.point_moments) {
    m = order.monomial(m);
    m.resize(std::max(m.size(), channels));
    if (std::any_of(m.begin() + static_cast<std::ptrdiff_t>(channels), m.end(),
                    [](int e) { return e != 0; })) {
      throw std::logic_error("a point moment holds a computed channel");
    }
  }
  if (options.integration) {
    read_options.integration->integrals = order.values(options.integration->integrals);
  }
  const bool any_moments = !keys.empty();
  // Rows that depend on their neighbours across a shard's edge in ways the shard cannot see
  // (a shifted input, a row dropped between two, every other row kept) keep files whole.
  // So do filters, which run through each file from its start.
  const bool whole_files = options.input_shift != 0 || options.stride > 1 ||
                           options.record.layout.missing != MissingValues::kError ||
                           options.integration.has_value();
  const std::vector<DataSource::Shard> shards = source.shards(
      whole_files ? std::numeric_limits<std::size_t>::max() : options.record.control.shard_bytes);
  request.part.before = std::max<std::size_t>({max_lag_of(keys), options.lags, 1});
  request.part.after = MomentAccumulator::kLookaheadRows;

  // The first shard's reader gives the metadata, and with it the input hold.
  DataMoments out;
  std::unique_ptr<DataReader> first;
  std::exception_ptr open_error;
  try {
    first = source.open(shards.front(), request);
    out.metadata = first->metadata();
  } catch (...) {
    open_error = std::current_exception();
  }
  out.hold = input_hold(out.metadata, options);
  if (out.hold == InputHold::kZeroOrderHold && !inputs.empty() && !options.derivatives.empty()) {
    throw DataError({source.name(), 1, 1, ""},
                    "the inputs are held over each sample (input hold zoh), so the column '" +
                        options.derivatives.front() +
                        "', a derivative of a state they drive, jumps at every sample and its "
                        "products cannot be averaged over the intervals: record it with inputs "
                        "sampled as they vary (input hold 'sample'), or take the `measured` "
                        "statement out of the model");
  }
  // The merged state keeps the stretches of every shard, so that the batches are made the same
  // way whatever thread or process reads a shard: at least 8 per shard for few shards, one for
  // as many as four per batch (its memory grows by one stretch per shard: 16 MB of data).
  const std::size_t batches = options.batches > 0
                                  ? options.batches
                                  : std::max(DataOptions::kMaxAutoBatches, options.min_batches);
  const bool collapse = shards.size() >= 4 * batches;
  const std::size_t shard_batches =
      std::max<std::size_t>(2, (batches + shards.size() - 1) / shards.size());
  ChannelLayout layout(order.states, order.inputs, read_options.computed);
  std::vector<Moment> columns = in_columns(std::move(keys), order, layout);
  const PassSetup setup{std::move(columns), order.states,  order.inputs, std::move(layout),
                        out.hold,           shard_batches, collapse,     &read_options};
  const Pass pass{source, shards, request, setup, (shard_batches + 1) * shards.size()};
  RangeResult result;
  const auto read = [&] { result = read_all(pass, std::move(first), open_error, channels); };
  {
    // The reading touches no GiNaC object: calls on other threads use the algebra meanwhile. The
    // lock is let go outside around_pass, so that a front end's lock (Python's GIL) is always
    // taken before it, never while it is held.
    const AlgebraUnlock unlock;
    if (options.record.control.around_pass) {
      options.record.control.around_pass(read);
    } else {
      read();
    }
    // Before the readers' errors: a file cut short mid-row reads as a malformed row.
    check_unchanged(source, shared);
  }
  const std::optional<double> first_step = check_file_intervals(result, shards, paths, out);
  if (result.error) std::rethrow_exception(result.error);

  MomentAccumulator& accumulator = result.state->moments;
  accumulator.finish();
  check_record(source, *result.state, any_moments, shards.size(), options);
  out.rows = result.state->rows;
  out.runs = result.state->runs;
  out.time_step = options.record.dt ? options.record.dt : first_step;
  // --dt is checked before the pass, the record's own interval only now.
  if (out.time_step && !options.record.dt) {
    RecordOptions::check_record_interval(*out.time_step,
                                         {paths.empty() ? source.name() : paths.front(), 1, 1, ""});
  }
  if (out.time_step) *out.time_step *= static_cast<double>(options.stride);
  out.estimates = estimates(
      accumulator,
      options.batches > 0
          ? options.batches
          : std::clamp(std::max(accumulator.intervals() / DataOptions::kAutoBatchIntervals,
                                options.min_batches),
                       DataOptions::kMinAutoBatches, batches));
  out.channels = channel_statistics(result.state->lags, request.names, order,
                                    out.hold == InputHold::kZeroOrderHold && !inputs.empty());
  out.point_means = result.state->lags.point_means();
  return out;
}

}  // namespace momentid
