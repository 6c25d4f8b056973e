#pragma once
// The benchmarks' clock: wall-clock seconds of a stretch of work, and the median of repeated
// calls, so that every program times its work and its baseline the same way.

#include <algorithm>
#include <chrono>
#include <vector>

// Wall-clock seconds since it was made (a monotonic clock).
class Stopwatch {
 public:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// The median wall-clock seconds of `repetitions` calls of `f` (one at least).
template <typename F>
double median_seconds(int repetitions, F&& f) {
  std::vector<double> times;
  for (int r = 0; r < std::max(repetitions, 1); ++r) {
    const Stopwatch clock;
    f();
    times.push_back(clock.seconds());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}
