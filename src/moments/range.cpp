#include "moments/range.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace momentid {
namespace {

// The empty sums of a pass, into which its shards are merged.
ShardState empty_state(const Pass& pass) {
  const PassSetup& setup = pass.setup;
  return ShardState{
      MomentAccumulator(setup.moments, setup.layout.states, setup.layout.inputs, setup.hold,
                        pass.merged_batches, setup.options->held_rule),
      LagSums(setup.states + setup.inputs, setup.options->lags, setup.options->point_moments)};
}

// Shards [begin, end) read by `workers` threads, each taking the next shard not yet started,
// and merged in record order as they finish (a shard that finishes early waits in `done_`).
class RangeReading {
 public:
  RangeReading(const Pass& pass, std::size_t begin, std::size_t end,
               std::unique_ptr<DataReader> first_reader, std::size_t workers, bool pipelined,
               RangeResult& out)
      : pass_(pass),
        options_(*pass.setup.options),
        begin_(begin),
        end_(end),
        first_reader_(std::move(first_reader)),
        pipelined_(pipelined),
        out_(out),
        done_(end - begin),
        next_shard_(begin),
        next_merge_(begin),
        running_(workers),
        partial_(workers) {}

  // A worker's loop: reads shards until none is left or one before has failed.
  void work(std::size_t worker) {
    for (;;) {
      std::size_t k;
      std::unique_ptr<DataReader> reader;
      {
        std::lock_guard lock(mutex_);
        if (next_shard_ >= std::min(end_, out_.first_error)) break;
        k = next_shard_++;
        if (k == begin_) reader = std::move(first_reader_);
      }
      std::exception_ptr error;
      std::optional<ShardState> state = read(k, std::move(reader), worker, error);
      std::lock_guard lock(mutex_);
      if (error) {
        fail_at(k, error);
      } else {
        done_[k - begin_] = std::move(state);
      }
      merge_ready();
    }
    std::lock_guard lock(mutex_);
    --running_;
    finished_.notify_all();
  }

  // Waits for the workers, reporting the progress a few times a second.
  void wait() {
    std::unique_lock lock(mutex_);
    while (running_ > 0) {
      finished_.wait_for(lock, std::chrono::milliseconds(100));
      if (options_.record.control.interrupted && running_ > 0 && !interrupted_) {
        lock.unlock();
        const bool stop = options_.record.control.interrupted();
        lock.lock();
        // No shard is started after this one; those being read finish. Asked no more: the
        // caller has its answer (Python's KeyboardInterrupt is set).
        if (stop) {
          interrupted_ = true;
          fail_at(begin_, std::make_exception_ptr(Interrupted()));
        }
      }
      if (options_.record.control.progress && running_ > 0) {
        double shards_done = static_cast<double>(next_merge_ - begin_);
        for (const std::atomic<double>& f : partial_) shards_done += f;
        const double fraction = std::min(1.0, shards_done / static_cast<double>(end_ - begin_));
        lock.unlock();
        options_.record.control.progress(rows_done_, fraction);
        lock.lock();
      }
    }
  }

  std::size_t rows_done() const { return rows_done_; }

 private:
  std::optional<ShardState> read(std::size_t k, std::unique_ptr<DataReader> reader,
                                 std::size_t worker, std::exception_ptr& error) {
    std::optional<ShardState> state;
    try {
      if (!reader) reader = pass_.source.open(pass_.shards[k], pass_.request);
      partial_[worker] = 0;
      state = read_shard(*reader, pass_.shards[k].count == 1, pass_.setup, pipelined_, rows_done_,
                         partial_[worker]);
      partial_[worker] = 0;
    } catch (...) {
      error = std::current_exception();
    }
    return state;
  }

  void fail_at(std::size_t k, std::exception_ptr error) {
    if (k < out_.first_error) {
      out_.first_error = k;
      out_.error = error;
    }
  }

  // Merges the finished shards that come next in record order (mutex held).
  void merge_ready() {
    while (next_merge_ < std::min(end_, out_.first_error) && done_[next_merge_ - begin_]) {
      ShardState shard = std::move(*done_[next_merge_ - begin_]);
      done_[next_merge_ - begin_].reset();
      try {
        out_.state->moments.merge(std::move(shard.moments));
        out_.state->lags.merge(shard.lags);
        out_.state->rows += shard.rows;
        out_.state->runs += shard.runs;
        out_.summaries.push_back(std::move(shard.summary));
      } catch (...) {
        fail_at(next_merge_, std::current_exception());
      }
      ++next_merge_;
    }
  }

  const Pass& pass_;
  const DataOptions& options_;
  std::size_t begin_, end_;
  std::unique_ptr<DataReader> first_reader_;
  bool pipelined_;
  RangeResult& out_;
  std::mutex mutex_;
  std::condition_variable finished_;
  std::vector<std::optional<ShardState>> done_;
  std::size_t next_shard_, next_merge_, running_;
  bool interrupted_ = false;
  std::atomic<std::size_t> rows_done_{0};
  // How far each worker is in its shard, when it can tell.
  std::vector<std::atomic<double>> partial_;
};

}  // namespace

RangeResult read_range(const Pass& pass, std::size_t begin, std::size_t end,
                       std::unique_ptr<DataReader> first_reader) {
  const DataOptions& options = *pass.setup.options;
  RangeResult out;
  out.state.emplace(empty_state(pass));
  if (begin == end) return out;
  const std::size_t threads = options.record.control.threads > 0
                                  ? options.record.control.threads
                                  : std::max<unsigned>(1, std::thread::hardware_concurrency());
  const std::size_t workers = std::min(threads, end - begin);
  // With threads to spare, each shard is read on one thread while it is accumulated on another.
  const bool pipelined = threads >= 2 * workers;
  RangeReading reading(pass, begin, end, std::move(first_reader), workers, pipelined, out);
  std::vector<std::thread> pool;
  for (std::size_t w = 0; w < workers; ++w) pool.emplace_back([&reading, w] { reading.work(w); });
  reading.wait();
  for (std::thread& t : pool) t.join();
  if (options.record.control.progress && !out.error)
    options.record.control.progress(reading.rows_done(), 1.0);
  return out;
}

}  // namespace momentid
