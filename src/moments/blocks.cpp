#include "moments/blocks.hpp"

#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace momentid {
namespace {

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

void for_each_block(DataReader& reader, bool pipelined,
                    const std::function<void(DataBlock&)>& consume) {
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

}  // namespace momentid
