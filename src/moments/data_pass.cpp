#include "momentid/data_pass.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string_view>
#include <thread>

#include "common/bytes.hpp"
#include "common/cluster.hpp"
#include "data/formats.hpp"
#include "data/text.hpp"

namespace momentid {
namespace {

using data::plural;

constexpr std::size_t kBlockRows = 1 << 15;

// Strings in the result of another process: a length, then the bytes.
void put_text(ByteWriter& out, std::string_view text) {
  out.u64(text.size());
  out.bytes(text.data(), text.size());
}

std::string get_text(ByteReader& in) {
  const auto bytes = in.take(in.count(1, "characters"), "a text");
  return {bytes.begin(), bytes.end()};
}

// Sums for the mean, variance and lagged products of every channel, over pairs within runs.
// Values are summed less an offset, the first row's, so that a large mean does not cancel the
// variance away in sum(x^2)/n - mean^2. Sums of shards merge: the pairs a shard owns are those
// whose later row is its own, and their earlier rows may come from the rows before the shard
// (add_history).
class LagSums {
 public:
  LagSums(std::size_t channels, std::size_t lags)
      : channels_(channels),
        lags_(lags),
        history_(lags * channels, 0.0),
        sum_(channels, 0.0),
        sum_squares_(channels, 0.0),
        products_(lags * channels, 0.0),
        lead_(lags * channels, 0.0),
        lagged_(lags * channels, 0.0),
        pairs_(lags, 0) {}

  void start_run() { filled_ = 0; }

  // Rows of the run before the shard, which only pair with the shard's own rows.
  void add_history(const double* rows, std::size_t count) {
    for (std::size_t r = 0; r < count; ++r) remember(rows + r * channels_);
  }

  void add(const double* rows, std::size_t count) {
    for (std::size_t r = 0; r < count; ++r) {
      const double* const row = rows + r * channels_;
      if (count_ == 0) offset_.assign(row, row + channels_);
      for (std::size_t c = 0; c < channels_; ++c) {
        const double x = row[c] - offset_[c];
        sum_[c] += x;
        sum_squares_[c] += x * x;
      }
      // history_ holds the previous `lags_` rows, newest first at `head_`.
      for (std::size_t l = 0, slot = head_; l < std::min(filled_, lags_); ++l) {
        const double* past = &history_[slot * channels_];
        if (++slot == lags_) slot = 0;
        for (std::size_t c = 0; c < channels_; ++c) {
          const double x = row[c] - offset_[c], y = past[c] - offset_[c];
          products_[l * channels_ + c] += x * y;
          lead_[l * channels_ + c] += x;
          lagged_[l * channels_ + c] += y;
        }
        ++pairs_[l];
      }
      remember(row);
      ++count_;
    }
  }

  // The sums, for another process (load()).
  void save(ByteWriter& out) const {
    out.u64(count_);
    for (const auto* v : {&offset_, &sum_, &sum_squares_, &products_, &lead_, &lagged_}) {
      out.u64(v->size());
      for (double x : *v) out.f64(x);
    }
    for (std::size_t p : pairs_) out.u64(p);
  }
  static LagSums load(ByteReader& in, std::size_t channels, std::size_t lags) {
    LagSums out(channels, lags);
    out.count_ = in.u64("the row count of the channel sums");
    for (auto* v :
         {&out.offset_, &out.sum_, &out.sum_squares_, &out.products_, &out.lead_, &out.lagged_}) {
      const std::uint64_t n = in.u64("a count of channel sums");
      if (n != v->size() && !(v == &out.offset_ && n == channels)) {
        throw Error("the result of another process does not match this one's channels");
      }
      v->resize(n);
      for (double& x : *v) x = in.f64("a channel sum");
    }
    for (std::size_t& p : out.pairs_) p = in.u64("a count of pairs");
    return out;
  }

  // Adds the sums of `other`, the shard after this one's rows.
  void merge(const LagSums& other) {
    if (other.count_ == 0) return;
    if (count_ == 0) {
      *this = other;
      return;
    }
    for (std::size_t c = 0; c < channels_; ++c) {
      // other's values less this offset: x - o = (x - o_other) - d.
      const double d = offset_[c] - other.offset_[c];
      const auto n = static_cast<double>(other.count_);
      sum_[c] += other.sum_[c] - n * d;
      sum_squares_[c] += other.sum_squares_[c] - 2 * d * other.sum_[c] + n * d * d;
      for (std::size_t l = 0; l < lags_; ++l) {
        const std::size_t i = l * channels_ + c;
        const auto p = static_cast<double>(other.pairs_[l]);
        products_[i] += other.products_[i] - d * (other.lead_[i] + other.lagged_[i]) + p * d * d;
        lead_[i] += other.lead_[i] - p * d;
        lagged_[i] += other.lagged_[i] - p * d;
      }
    }
    for (std::size_t l = 0; l < lags_; ++l) pairs_[l] += other.pairs_[l];
    count_ += other.count_;
  }

  ChannelStatistics statistics(std::size_t c) const {
    ChannelStatistics s;
    const double n = static_cast<double>(count_);
    const double shifted_mean = sum_[c] / n;
    s.mean = offset_[c] + shifted_mean;
    s.variance = sum_squares_[c] / n - shifted_mean * shifted_mean;
    s.correlation_time = lags_ + 1;
    // The lag-l covariance about the record's mean over the pairs that lag has. The values
    // paired are not all the values (a run's first l rows lead no pair, its last l are lagged by
    // none), so the pairs' own sums enter: on short runs their means are not the record's.
    for (std::size_t l = 0; l < lags_; ++l) {
      const std::size_t i = l * channels_ + c;
      const auto p = static_cast<double>(pairs_[l]);
      const double rho = pairs_[l] > 0 && s.variance > 0
                             ? ((products_[i] - shifted_mean * (lead_[i] + lagged_[i])) / p +
                                shifted_mean * shifted_mean) /
                                   s.variance
                             : std::nan("");
      s.autocorrelation.push_back(rho);
      if (s.correlation_time == lags_ + 1 && rho < std::exp(-1.0)) s.correlation_time = l + 1;
    }
    // White noise adds to the autocovariance at lag 0 only: the excess of R(0) over the
    // extrapolation a + b s^2 + c |s|^3 + d s^4 through R(1) .. R(4) estimates its variance.
    // (The |s|^3 term is that of a state whose derivative jumps with a held input.)
    if (lags_ >= 4 && s.variance > 0) {
      const auto& rho = s.autocorrelation;
      const double smooth = 1.92 * rho[0] - 1.44 * rho[1] + 0.64 * rho[2] - 0.12 * rho[3];
      s.noise_variance = s.variance * (1 - smooth);
    }
    return s;
  }

 private:
  void remember(const double* row) {
    if (lags_ > 0) {
      head_ = head_ == 0 ? lags_ - 1 : head_ - 1;
      std::copy(row, row + channels_, &history_[head_ * channels_]);
    }
    ++filled_;
  }

  std::size_t channels_, lags_;
  std::vector<double> history_, offset_, sum_, sum_squares_, products_;
  // Per lag and channel: the sums of the later and of the earlier values of the pairs.
  std::vector<double> lead_, lagged_;
  std::vector<std::size_t> pairs_;
  std::size_t head_ = 0, filled_ = 0, count_ = 0;
};

// Pairs input row n with state row n + shift within a run (`--input-shift`), for data whose
// input and state channels are not aligned in time. Rows without a partner are dropped.
class InputShift {
 public:
  InputShift(std::size_t states, std::size_t inputs, long shift)
      : states_(states), inputs_(inputs), shift_(shift) {}

  void start_run() { past_.clear(); }

  // The shifted rows for `count` new rows (states, then inputs).
  const std::vector<double>& apply(const double* rows, std::size_t count) {
    const std::size_t width = states_ + inputs_;
    const std::size_t lag = static_cast<std::size_t>(shift_ < 0 ? -shift_ : shift_);
    out_.clear();
    for (std::size_t r = 0; r < count; ++r) {
      const double* row = rows + r * width;
      if (past_.size() == lag) {
        // shift > 0: the states of this row with the inputs of `lag` rows ago; shift < 0: the
        // states of `lag` rows ago with the inputs of this row.
        const double* early = lag == 0 ? row : past_.front().data();
        const double* states = shift_ >= 0 ? row : early;
        const double* inputs = shift_ >= 0 ? early : row;
        out_.insert(out_.end(), states, states + states_);
        out_.insert(out_.end(), inputs + states_, inputs + width);
      }
      if (lag > 0) {
        if (past_.size() == lag) past_.pop_front();
        past_.emplace_back(row, row + width);
      }
    }
    return out_;
  }

 private:
  std::size_t states_, inputs_;
  long shift_;
  std::deque<std::vector<double>> past_;
  std::vector<double> out_;
};

// Hands filled blocks from the reading thread to the accumulating one, two at a time at most.
class BlockQueue {
 public:
  explicit BlockQueue(std::size_t capacity) : free_(capacity) {
    for (auto& b : free_) b = std::make_unique<DataBlock>();
  }
  std::unique_ptr<DataBlock> take_free() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return !free_.empty() || stop_; });
    if (stop_) return nullptr;
    auto b = std::move(free_.back());
    free_.pop_back();
    return b;
  }
  void give_free(std::unique_ptr<DataBlock> b) {
    std::lock_guard lock(mutex_);
    free_.push_back(std::move(b));
    changed_.notify_all();
  }
  void push_full(std::unique_ptr<DataBlock> b) {
    std::lock_guard lock(mutex_);
    full_.push_back(std::move(b));
    changed_.notify_all();
  }
  // nullptr when the reader has finished (or failed) and everything has been taken.
  std::unique_ptr<DataBlock> take_full() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return !full_.empty() || done_; });
    if (full_.empty()) return nullptr;
    auto b = std::move(full_.front());
    full_.erase(full_.begin());
    return b;
  }
  void finish(std::exception_ptr error) {
    std::lock_guard lock(mutex_);
    done_ = true;
    error_ = error;
    changed_.notify_all();
  }
  void stop() {
    std::lock_guard lock(mutex_);
    stop_ = true;
    changed_.notify_all();
  }
  std::exception_ptr error() {
    std::lock_guard lock(mutex_);
    return error_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<std::unique_ptr<DataBlock>> free_, full_;
  bool done_ = false, stop_ = false;
  std::exception_ptr error_;
};

// Delivers the blocks of `reader` to `consume`, in order. `pipelined`: the reader runs on a
// thread of its own, a few blocks ahead.
template <class Consume>
void for_each_block(DataReader& reader, bool pipelined, Consume&& consume) {
  if (!pipelined) {
    DataBlock block;
    while (reader.next(block, kBlockRows)) consume(block);
    return;
  }
  BlockQueue queue(3);
  std::thread producer([&] {
    try {
      while (auto block = queue.take_free()) {
        if (!reader.next(*block, kBlockRows)) {
          queue.give_free(std::move(block));
          break;
        }
        queue.push_full(std::move(block));
      }
      queue.finish(nullptr);
    } catch (...) {
      queue.finish(std::current_exception());
    }
  });
  try {
    while (auto block = queue.take_full()) {
      consume(*block);
      queue.give_free(std::move(block));
    }
  } catch (...) {
    queue.stop();
    producer.join();
    throw;
  }
  producer.join();
  if (auto error = queue.error()) std::rethrow_exception(error);
}

// What every shard's pass shares.
struct PassSetup {
  std::vector<Moment> moments;
  std::size_t states = 0, inputs = 0;
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
// rows after it only to close its last intervals.
// Every `stride`-th row of each run from row `phase` on (DataOptions::stride).
class Decimate {
 public:
  Decimate(std::size_t width, std::size_t stride, std::size_t phase)
      : width_(width), stride_(stride), phase_(phase) {}

  void start_run() { row_ = 0; }

  const std::vector<double>& apply(const double* rows, std::size_t count) {
    out_.clear();
    for (std::size_t r = 0; r < count; ++r, ++row_) {
      if (row_ >= phase_ && (row_ - phase_) % stride_ == 0) {
        out_.insert(out_.end(), rows + r * width_, rows + (r + 1) * width_);
      }
    }
    return out_;
  }

 private:
  std::size_t width_, stride_, phase_, row_ = 0;
  std::vector<double> out_;
};

ShardState read_shard(DataReader& reader, bool whole, const PassSetup& setup, bool pipelined,
                      std::atomic<std::size_t>& rows_done, std::atomic<double>& fraction) {
  const DataOptions& options = *setup.options;
  const std::size_t channels = setup.states + setup.inputs;
  ShardState out{MomentAccumulator(setup.moments, setup.states, setup.inputs, setup.hold,
                                   setup.batches, options.held_rule),
                 LagSums(channels, options.lags)};
  InputShift shift(setup.states, setup.inputs, options.input_shift);
  Decimate decimate(channels, options.stride, options.phase);
  std::vector<double> history;  // of the current run, before the shard
  const std::size_t history_values = out.moments.max_lag() * channels;
  bool owned = false;
  for_each_block(reader, pipelined, [&](DataBlock& block) {
    if (!options.offsets.empty()) {
      double* values = block.values.data();
      for (std::size_t r = 0; r < block.rows; ++r) {
        for (std::size_t c = 0; c < channels; ++c) values[r * channels + c] -= options.offsets[c];
      }
    }
    const double* const values = block.values.data();
    switch (block.zone) {
      case RowZone::kBefore:
        if (block.run_starts) {
          history.clear();
          out.lags.start_run();
        }
        history.insert(history.end(), values, values + block.rows * channels);
        if (history.size() > history_values) {
          history.erase(history.begin(),
                        history.end() - static_cast<std::ptrdiff_t>(history_values));
        }
        out.lags.add_history(values, block.rows);
        return;
      case RowZone::kAfter:
        if (owned) out.moments.add_lookahead(values, block.rows);
        return;
      case RowZone::kOwned:
        break;
    }
    if (block.run_starts) {
      shift.start_run();
      decimate.start_run();
      out.moments.start_run();
      out.lags.start_run();
      ++out.runs;
    } else if (!owned) {
      out.moments.continue_run();
      if (!history.empty()) out.moments.add_history(history.data(), history.size() / channels);
    }
    owned = true;
    const double* rows = values;
    std::size_t count = block.rows;
    if (options.input_shift != 0) {
      const std::vector<double>& shifted = shift.apply(rows, count);
      rows = shifted.data();
      count = shifted.size() / channels;
    }
    if (options.stride > 1) {
      const std::vector<double>& kept = decimate.apply(rows, count);
      rows = kept.data();
      count = kept.size() / channels;
    }
    out.moments.add(rows, count);
    out.lags.add(values, block.rows);
    out.rows += block.rows;
    rows_done += block.rows;
    // A part of a file cannot tell how far it is; a whole file can.
    if (options.control.progress && whole) {
      fraction = reader.fraction_read().value_or(0);
    }
  });
  out.moments.finish();
  if (setup.collapse) out.moments.collapse();
  out.summary = {reader.steps(), reader.time_step(), reader.missing()};
  return out;
}

// A file's sample interval, from the steps of its shards (else from elsewhere: the metadata,
// --dt).
std::optional<double> file_step(const DataReader::Steps& steps, std::optional<double> other) {
  return steps.count > 0 ? std::optional(steps.sum / static_cast<double>(steps.count)) : other;
}

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
// shards after it from starting. Nothing throws out of it.
RangeResult read_range(const Pass& pass, std::size_t begin, std::size_t end,
                       std::unique_ptr<DataReader> first_reader) {
  const DataOptions& options = *pass.setup.options;
  RangeResult out;
  out.state.emplace(
      ShardState{MomentAccumulator(pass.setup.moments, pass.setup.states, pass.setup.inputs,
                                   pass.setup.hold, pass.merged_batches, options.held_rule),
                 LagSums(pass.setup.states + pass.setup.inputs, options.lags)});
  if (begin == end) return out;
  const std::size_t threads = options.control.threads > 0
                                  ? options.control.threads
                                  : std::max<unsigned>(1, std::thread::hardware_concurrency());
  const std::size_t workers = std::min(threads, end - begin);
  const bool pipelined = threads >= 2 * workers;

  std::mutex mutex;
  std::condition_variable finished;
  std::vector<std::optional<ShardState>> done(end - begin);
  std::size_t next_shard = begin, next_merge = begin, running = workers;
  std::atomic<std::size_t> rows_done{0};
  // How far each worker is in its shard, when it can tell.
  std::vector<std::atomic<double>> partial(workers);
  const auto fail_at = [&](std::size_t k, std::exception_ptr error) {
    if (k < out.first_error) {
      out.first_error = k;
      out.error = error;
    }
  };
  // Merges the finished shards that come next in record order (mutex held).
  const auto merge_ready = [&] {
    while (next_merge < std::min(end, out.first_error) && done[next_merge - begin]) {
      ShardState shard = std::move(*done[next_merge - begin]);
      done[next_merge - begin].reset();
      try {
        out.state->moments.merge(shard.moments);
        out.state->lags.merge(shard.lags);
        out.state->rows += shard.rows;
        out.state->runs += shard.runs;
        out.summaries.push_back(std::move(shard.summary));
      } catch (...) {
        fail_at(next_merge, std::current_exception());
      }
      ++next_merge;
    }
  };
  const auto work = [&](std::size_t worker) {
    for (;;) {
      std::size_t k;
      std::unique_ptr<DataReader> reader;
      {
        std::lock_guard lock(mutex);
        if (next_shard >= std::min(end, out.first_error)) break;
        k = next_shard++;
        if (k == begin) reader = std::move(first_reader);
      }
      std::optional<ShardState> state;
      std::exception_ptr error;
      try {
        if (!reader) reader = pass.source.open(pass.shards[k], pass.request);
        partial[worker] = 0;
        state = read_shard(*reader, pass.shards[k].count == 1, pass.setup, pipelined, rows_done,
                           partial[worker]);
        partial[worker] = 0;
      } catch (...) {
        error = std::current_exception();
      }
      reader.reset();
      std::lock_guard lock(mutex);
      if (error) {
        fail_at(k, error);
      } else {
        done[k - begin] = std::move(state);
      }
      merge_ready();
    }
    std::lock_guard lock(mutex);
    --running;
    finished.notify_all();
  };
  std::vector<std::thread> pool;
  for (std::size_t w = 0; w < workers; ++w) pool.emplace_back(work, w);
  {
    std::unique_lock lock(mutex);
    while (running > 0) {
      finished.wait_for(lock, std::chrono::milliseconds(100));
      if (options.control.progress && running > 0) {
        double shards_done = static_cast<double>(next_merge - begin);
        for (const std::atomic<double>& f : partial) shards_done += f;
        const double fraction = std::min(1.0, shards_done / static_cast<double>(end - begin));
        lock.unlock();
        options.control.progress(rows_done, fraction);
        lock.lock();
      }
    }
  }
  for (std::thread& t : pool) t.join();
  if (options.control.progress && !out.error) options.control.progress(rows_done, 1.0);
  return out;
}

void write_optional(ByteWriter& out, const std::optional<double>& v) {
  out.u64(v ? 1 : 0);
  out.f64(v.value_or(0));
}

std::optional<double> read_optional(ByteReader& in) {
  const bool has = in.u64("whether a value is there") != 0;
  const double v = in.f64("a value");
  return has ? std::optional(v) : std::nullopt;
}

void write_location(ByteWriter& out, const SourceLocation& at) {
  put_text(out, at.file);
  out.i32(at.line);
  out.i32(at.column);
  put_text(out, at.text);
}

SourceLocation read_location(ByteReader& in) {
  SourceLocation at;
  at.file = get_text(in);
  at.line = in.i32("a line");
  at.column = in.i32("a column");
  at.text = get_text(in);
  return at;
}

// An error as another process rethrows it: its kind, place and message.
enum class ErrorKind : std::uint64_t { kData = 1, kUsage, kOther };

void write_error(ByteWriter& out, const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const DataError& e) {
    out.u64(static_cast<std::uint64_t>(ErrorKind::kData));
    write_location(out, e.location());
    put_text(out, e.message());
  } catch (const UsageError& e) {
    out.u64(static_cast<std::uint64_t>(ErrorKind::kUsage));
    put_text(out, e.what());
  } catch (const std::exception& e) {
    out.u64(static_cast<std::uint64_t>(ErrorKind::kOther));
    put_text(out, e.what());
  }
}

std::exception_ptr read_error(ByteReader& in) {
  switch (static_cast<ErrorKind>(in.u64("the kind of an error"))) {
    case ErrorKind::kData: {
      SourceLocation at = read_location(in);
      return std::make_exception_ptr(DataError(std::move(at), get_text(in)));
    }
    case ErrorKind::kUsage:
      return std::make_exception_ptr(UsageError(get_text(in)));
    default:
      return std::make_exception_ptr(Error(get_text(in)));
  }
}

std::vector<std::uint8_t> encode(const RangeResult& r) {
  ByteWriter out;
  const std::vector<std::uint8_t> moments = r.state->moments.serialize();
  out.u64(moments.size());
  out.bytes(reinterpret_cast<const char*>(moments.data()), moments.size());
  r.state->lags.save(out);
  out.u64(r.state->rows);
  out.u64(r.state->runs);
  out.u64(r.summaries.size());
  for (const ShardSummary& s : r.summaries) {
    out.u64(s.steps.count);
    out.f64(s.steps.sum);
    write_optional(out, s.time_step);
    out.u64(s.missing.rows);
    out.u64(s.missing.splits);
    out.u64(s.missing.joins);
    out.u64(s.missing.first ? 1 : 0);
    if (s.missing.first) write_location(out, *s.missing.first);
  }
  out.u64(r.error ? r.first_error : std::numeric_limits<std::uint64_t>::max());
  if (r.error) write_error(out, r.error);
  return out.take();
}

RangeResult decode(const std::vector<std::uint8_t>& bytes, std::size_t channels, std::size_t lags) {
  ByteReader in(bytes, "the bytes of another process");
  RangeResult r;
  MomentAccumulator moments =
      MomentAccumulator::deserialize(in.take(in.count(1, "accumulator bytes"), "its state"));
  LagSums sums = LagSums::load(in, channels, lags);
  r.state.emplace(ShardState{std::move(moments), std::move(sums)});
  r.state->rows = in.u64("the row count");
  r.state->runs = in.u64("the run count");
  r.summaries.resize(in.count(8, "shard summaries"));
  for (ShardSummary& s : r.summaries) {
    s.steps.count = in.u64("a step count");
    s.steps.sum = in.f64("a sum of steps");
    s.time_step = read_optional(in);
    s.missing.rows = in.u64("a count of missing rows");
    s.missing.splits = in.u64("a count of splits");
    s.missing.joins = in.u64("a count of joins");
    if (in.u64("whether a missing row is located") != 0) s.missing.first = read_location(in);
  }
  const std::uint64_t first_error = in.u64("the first failed shard");
  if (first_error != std::numeric_limits<std::uint64_t>::max()) {
    r.first_error = static_cast<std::size_t>(first_error);
    r.error = read_error(in);
  }
  return r;
}

// The ranges of all processes, merged in record order (each range's result, in rank order).
RangeResult merge_ranges(std::vector<RangeResult> ranges) {
  RangeResult out = std::move(ranges.front());
  for (std::size_t r = 1; r < ranges.size(); ++r) {
    RangeResult& next = ranges[r];
    if (out.error) break;
    out.state->moments.merge(next.state->moments);
    out.state->lags.merge(next.state->lags);
    out.state->rows += next.state->rows;
    out.state->runs += next.state->runs;
    for (ShardSummary& s : next.summaries) out.summaries.push_back(std::move(s));
    out.first_error = next.first_error;
    out.error = next.error;
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
  const bool several_files = paths.size() > 1;
  ColumnRequest request;
  request.names = states;
  request.names.insert(request.names.end(), inputs.begin(), inputs.end());
  request.rename = options.rename;
  // Several files: the minimum is the whole record's, checked at its end.
  request.min_rows = several_files ? 0 : options.min_rows;
  request.dt = options.dt;
  request.layout = options.layout;
  const std::size_t channels = request.names.size();
  if (!options.offsets.empty() && options.offsets.size() != channels) {
    throw std::invalid_argument("moments_from_data: one offset per channel needed");
  }
  const bool any_moments = !keys.empty();
  std::size_t max_lag = 0;
  for (const Moment& m : keys) {
    for (const MomentFactor& f : m.factors()) {
      max_lag = std::max(max_lag, static_cast<std::size_t>(f.lag));
    }
  }
  // Rows that depend on their neighbours across a shard's edge in ways the shard cannot see
  // (a shifted input, a row dropped between two, every other row kept) keep files whole.
  const bool whole_files = options.input_shift != 0 || options.stride > 1 ||
                           options.layout.missing != MissingValues::kError;
  const std::vector<DataSource::Shard> shards = source.shards(
      whole_files ? std::numeric_limits<std::size_t>::max() : options.control.shard_bytes);
  request.part.before = std::max<std::size_t>({max_lag, options.lags, 1});
  request.part.after = MomentAccumulator::kLookaheadRows;

  // With several processes (MPI), each reads a contiguous range of the shards.
  const bool shared = options.control.across_processes;
  const std::size_t ranks = shared ? static_cast<std::size_t>(cluster::size()) : 1;
  const std::size_t rank = shared ? static_cast<std::size_t>(cluster::rank()) : 0;
  const std::size_t begin = shards.size() * rank / ranks;
  const std::size_t end = shards.size() * (rank + 1) / ranks;

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
  if (options.hold) {
    out.hold = *options.hold;
  } else {
    out.hold = out.metadata.input_hold();
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
  const PassSetup setup{keys,          states.size(), inputs.size(), out.hold,
                        shard_batches, collapse,      &options};
  const Pass pass{source, shards, request, setup, (shard_batches + 1) * shards.size()};
  RangeResult result;
  if (open_error) {
    result = read_range(pass, 0, 0, nullptr);
    result.first_error = 0;
    result.error = open_error;
  } else {
    result = read_range(pass, begin, end, begin == 0 ? std::move(first) : nullptr);
  }
  if (ranks > 1) {
    std::vector<RangeResult> ranges;
    for (const std::vector<std::uint8_t>& bytes : cluster::all_gather(encode(result))) {
      ranges.push_back(decode(bytes, channels, options.lags));
    }
    result = merge_ranges(std::move(ranges));
  }

  // Each file's interval must be the first file's: checked in record order, up to the first
  // shard that failed.
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
  if (result.error) std::rethrow_exception(result.error);

  MomentAccumulator& accumulator = result.state->moments;
  accumulator.finish();
  if (result.state->rows < options.min_rows && (several_files || shards.size() > 1)) {
    throw DataError({paths.empty() ? source.name() : paths.back(), 1, 1, ""},
                    "the data have " + plural(result.state->rows, "row") +
                        (several_files ? " in " + plural(paths.size(), "file") : std::string()) +
                        "; at least " + std::to_string(options.min_rows) + " are needed");
  }
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
  out.rows = result.state->rows;
  out.runs = result.state->runs;
  out.time_step = options.dt ? options.dt : first_step;
  if (out.time_step) *out.time_step *= static_cast<double>(options.stride);
  out.estimates = estimates(
      accumulator,
      options.batches > 0
          ? options.batches
          : std::clamp(std::max(accumulator.intervals() / DataOptions::kAutoBatchIntervals,
                                options.min_batches),
                       DataOptions::kMinAutoBatches, batches));
  for (std::size_t c = 0; c < channels; ++c) {
    ChannelStatistics s = result.state->lags.statistics(c);
    s.name = request.names[c];
    s.is_input = c >= states.size();
    out.channels.push_back(std::move(s));
  }
  return out;
}

}  // namespace momentid

namespace momentid {

std::optional<double> ChannelStatistics::noise_fraction() const {
  if (!noise_variance || !(variance > 0)) return std::nullopt;
  return std::sqrt(std::max(0.0, *noise_variance) / variance);
}

std::string missing_warning(const MissingSummary& missing) {
  const SourceLocation& at = *missing.first;
  std::string text = "dropped " + std::to_string(missing.rows) +
                     (missing.rows == 1 ? " row" : " rows") +
                     " with missing values (the first at " + at.file + ":" +
                     std::to_string(at.line) + ":" + std::to_string(at.column) + ")";
  if (missing.splits > 0) {
    text += " and began a new run at " + std::to_string(missing.splits) +
            (missing.splits == 1 ? " place" : " places");
  }
  if (missing.joins > 0) {
    text += " and joined their neighbours at " + std::to_string(missing.joins) +
            (missing.joins == 1 ? " place" : " places") +
            " as consecutive samples, which is right only for gaps short against the dynamics "
            "(--missing split-run starts a new run instead)";
  }
  return text;
}

std::vector<std::string> data_warnings(const DataMoments& data) {
  std::vector<std::string> out;
  if (data.missing.rows > 0) out.push_back(missing_warning(data.missing));
  for (const ChannelStatistics& c : data.channels) {
    if (c.autocorrelation.empty() || std::isnan(c.autocorrelation[0])) continue;
    const double rho = c.autocorrelation[0];
    char text[32];
    std::snprintf(text, sizeof text, "%.3f", rho);
    if (c.is_input && rho < 0.5) {
      out.push_back("input '" + c.name + "' is nearly white (lag-1 autocorrelation " + text +
                    "): the method needs a smooth input, and the estimates will be biased");
    } else if (!c.is_input && rho < 0.9) {
      out.push_back("sampling is coarse for the dynamics: the lag-1 autocorrelation of '" + c.name +
                    "' is " + text + "; the time averages are biased, sample faster if you can");
    }
  }
  return out;
}

}  // namespace momentid
