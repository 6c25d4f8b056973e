#include "momentid/data_pass.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace momentid {
namespace {

constexpr std::size_t kBlockRows = 1 << 15;

// Sums for the mean, variance and lagged products of every channel, over pairs within runs.
class LagSums {
 public:
  LagSums(std::size_t channels, std::size_t lags)
      : channels_(channels),
        lags_(lags),
        history_(lags * channels, 0.0),
        sum_(channels, 0.0),
        shifted_(channels, 0.0),
        sum_squares_(channels, 0.0),
        products_(lags * channels, 0.0),
        pairs_(lags, 0) {}

  void start_run() { filled_ = 0; }

  void add(const double* rows, std::size_t count) {
    for (std::size_t r = 0; r < count; ++r) {
      // Sums of values less the channel's first value: a large offset would otherwise cancel
      // the variance away in sum(x^2)/n - mean^2.
      if (count_ == 0) offset_.assign(rows, rows + channels_);
      for (std::size_t c = 0; c < channels_; ++c)
        shifted_[c] = rows[r * channels_ + c] - offset_[c];
      const double* x = shifted_.data();
      for (std::size_t c = 0; c < channels_; ++c) {
        sum_[c] += x[c];
        sum_squares_[c] += x[c] * x[c];
      }
      // history_ holds the previous `lags_` rows, newest first at `head_`.
      for (std::size_t l = 0; l < std::min(filled_, lags_); ++l) {
        const double* past = &history_[((head_ + l) % lags_) * channels_];
        for (std::size_t c = 0; c < channels_; ++c) products_[l * channels_ + c] += x[c] * past[c];
        ++pairs_[l];
      }
      if (lags_ > 0) {
        head_ = (head_ + lags_ - 1) % lags_;
        std::copy(x, x + channels_, &history_[head_ * channels_]);
      }
      ++filled_;
      ++count_;
    }
  }

  ChannelStatistics statistics(std::size_t c) const {
    ChannelStatistics s;
    const double n = static_cast<double>(count_);
    const double shifted_mean = sum_[c] / n;
    s.mean = offset_[c] + shifted_mean;
    s.variance = sum_squares_[c] / n - shifted_mean * shifted_mean;
    s.correlation_time = lags_ + 1;
    for (std::size_t l = 0; l < lags_; ++l) {
      const double rho = pairs_[l] > 0 && s.variance > 0
                             ? (products_[l * channels_ + c] / static_cast<double>(pairs_[l]) -
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
  std::size_t channels_, lags_;
  std::vector<double> history_, sum_, shifted_, offset_, sum_squares_, products_;
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
  ColumnRequest request;
  request.names = states;
  request.names.insert(request.names.end(), inputs.begin(), inputs.end());
  request.rename = options.rename;
  request.min_rows = options.min_rows;
  request.dt = options.dt;
  request.layout = options.layout;
  std::unique_ptr<DataReader> reader = source.open(request);

  DataMoments out;
  out.metadata = reader->metadata();
  if (options.hold) {
    out.hold = *options.hold;
  } else {
    const auto hold = out.metadata.get("input-hold");
    out.hold = hold && *hold == "zoh" ? InputHold::kZeroOrderHold : InputHold::kSample;
  }
  const std::size_t channels = request.names.size();
  if (!options.offsets.empty() && options.offsets.size() != channels) {
    throw std::invalid_argument("moments_from_data: one offset per channel needed");
  }
  const bool any_moments = !keys.empty();
  MomentAccumulator accumulator(std::move(keys), states.size(), inputs.size(), out.hold,
                                options.batches);
  LagSums lags(channels, options.lags);
  InputShift shift(states.size(), inputs.size(), options.input_shift);

  BlockQueue queue(3);
  // The reader's progress, as the producer last saw it (the reader is the producer's alone).
  std::atomic<double> fraction{-1};
  std::thread producer([&] {
    try {
      while (auto block = queue.take_free()) {
        if (!reader->next(*block, kBlockRows)) {
          queue.give_free(std::move(block));
          break;
        }
        if (options.progress) fraction = reader->fraction_read().value_or(-1);
        queue.push_full(std::move(block));
      }
      queue.finish(nullptr);
    } catch (...) {
      queue.finish(std::current_exception());
    }
  });
  try {
    while (auto block = queue.take_full()) {
      if (block->run_starts) {
        shift.start_run();
        accumulator.start_run();
        lags.start_run();
        ++out.runs;
      }
      if (!options.offsets.empty()) {
        double* values = block->values.data();
        for (std::size_t r = 0; r < block->rows; ++r) {
          for (std::size_t c = 0; c < channels; ++c) values[r * channels + c] -= options.offsets[c];
        }
      }
      if (options.input_shift == 0) {
        accumulator.add(block->values.data(), block->rows);
      } else {
        const std::vector<double>& shifted = shift.apply(block->values.data(), block->rows);
        accumulator.add(shifted.data(), shifted.size() / channels);
      }
      lags.add(block->values.data(), block->rows);
      out.rows += block->rows;
      if (options.progress) {
        const double f = fraction;
        options.progress(out.rows, f >= 0 ? std::optional<double>(f) : std::nullopt);
      }
      queue.give_free(std::move(block));
    }
  } catch (...) {
    queue.stop();
    producer.join();
    throw;
  }
  producer.join();
  if (auto error = queue.error()) std::rethrow_exception(error);

  accumulator.finish();
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
  out.time_step = reader->time_step();
  out.missing = reader->missing();
  out.estimates = estimates(accumulator, options.batches);
  for (std::size_t c = 0; c < channels; ++c) {
    ChannelStatistics s = lags.statistics(c);
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
