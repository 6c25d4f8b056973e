// The accumulator's stretches: their sums in slots carved from blocks of memory.

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <iterator>
#include <new>
#include <utility>

#include "momentid/accumulator.hpp"

namespace momentid {

namespace {

// The size of a large page, and of the blocks that ask for them.
constexpr std::size_t kLargePage = std::size_t{2} << 20;
// The slots of a stretch store's first block; each next block holds as many as those before.
constexpr std::size_t kFirstSlots = 16;

}  // namespace

void MomentAccumulator::Stretches::Free::operator()(double* block) const noexcept {
  std::free(block);
}

MomentAccumulator::Stretches::Stretches(const Stretches& other) : width_(other.width_) {
  for (const Slot& slot : other.slots_) append(slot.sums, slot.intervals);
}

MomentAccumulator::Stretches& MomentAccumulator::Stretches::operator=(const Stretches& other) {
  if (this != &other) *this = Stretches(other);
  return *this;
}

double* MomentAccumulator::Stretches::spare_slot() {
  if (spare_.empty()) {
    const std::size_t slots = std::max(kFirstSlots, capacity_);
    const std::size_t bytes = std::max<std::size_t>(slots * width_ * sizeof(double), 1);
    // A large block starts on a large page's boundary; its pages are taken as slots are used.
    void* memory =
        bytes >= kLargePage
            ? std::aligned_alloc(kLargePage, (bytes + kLargePage - 1) / kLargePage * kLargePage)
            : std::malloc(bytes);
    if (memory == nullptr) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    // A hint: where the system gives no large pages, the usual ones.
    if (bytes >= kLargePage) ::madvise(memory, bytes, MADV_HUGEPAGE);
#endif
    double* const block = static_cast<double*>(memory);
    blocks_.emplace_back(block);
    // Taken from the back: in the order of their addresses.
    for (std::size_t i = slots; i-- > 0;) spare_.push_back(block + i * width_);
    capacity_ += slots;
  }
  double* const slot = spare_.back();
  spare_.pop_back();
  return slot;
}

void MomentAccumulator::Stretches::append(const double* sums, std::size_t intervals) {
  double* const slot = spare_slot();
  if (sums != nullptr) {
    std::copy_n(sums, width_, slot);
  } else {
    std::fill_n(slot, width_, 0.0);
  }
  slots_.push_back({slot, intervals});
}

void MomentAccumulator::Stretches::add(std::size_t into, std::size_t from) {
  double* const to = slots_[into].sums;
  const double* const more = slots_[from].sums;
  for (std::size_t j = 0; j < width_; ++j) to[j] += more[j];
  slots_[into].intervals += slots_[from].intervals;
}

void MomentAccumulator::Stretches::truncate(std::size_t count) {
  for (std::size_t s = count; s < slots_.size(); ++s) spare_.push_back(slots_[s].sums);
  slots_.resize(std::min(count, slots_.size()));
}

void MomentAccumulator::Stretches::take(Stretches&& other) {
  for (const Slot& slot : other.slots_) {
    if (slot.intervals > 0) {
      slots_.push_back(slot);
    } else {
      spare_.push_back(slot.sums);
    }
  }
  spare_.insert(spare_.end(), other.spare_.begin(), other.spare_.end());
  std::move(other.blocks_.begin(), other.blocks_.end(), std::back_inserter(blocks_));
  capacity_ += other.capacity_;
  other.slots_.clear();
  other.spare_.clear();
  other.blocks_.clear();
  other.capacity_ = 0;
}

}  // namespace momentid
