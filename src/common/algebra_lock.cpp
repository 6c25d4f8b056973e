#include "momentid/algebra_lock.hpp"

#include <mutex>

namespace momentid {
namespace {

// A plain mutex and a count per thread rather than a std::recursive_mutex: the data pass lets go
// of every level a thread holds (AlgebraUnlock), which a recursive mutex cannot tell.
std::mutex& algebra_mutex() {
  static std::mutex mutex;
  return mutex;
}
thread_local int held = 0;

void take() {
  if (held++ == 0) algebra_mutex().lock();
}
void give_back() {
  if (--held == 0) algebra_mutex().unlock();
}

}  // namespace

AlgebraLock::AlgebraLock() { take(); }
AlgebraLock::~AlgebraLock() { give_back(); }

AlgebraUnlock::AlgebraUnlock() : held_(held) {
  if (held_ == 0) return;
  held = 0;
  algebra_mutex().unlock();
}
AlgebraUnlock::~AlgebraUnlock() {
  if (held_ == 0) return;
  algebra_mutex().lock();
  held = held_;
}

namespace detail {
AlgebraSpanStart::AlgebraSpanStart() { take(); }
AlgebraSpanStart::AlgebraSpanStart(const AlgebraSpanStart&) { take(); }
AlgebraSpanStart& AlgebraSpanStart::operator=(const AlgebraSpanStart&) {
  take();
  return *this;
}
AlgebraSpanStart::~AlgebraSpanStart() { give_back(); }

AlgebraSpanEnd::AlgebraSpanEnd() { give_back(); }
AlgebraSpanEnd::AlgebraSpanEnd(const AlgebraSpanEnd&) { give_back(); }
AlgebraSpanEnd& AlgebraSpanEnd::operator=(const AlgebraSpanEnd&) {
  give_back();
  return *this;
}
AlgebraSpanEnd::~AlgebraSpanEnd() { take(); }
}  // namespace detail

}  // namespace momentid
