#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace momentid::data {

// The precision to which a column of time stamps was written: the unit in the last decimal
// place of the value with the most decimals seen so far (1e-6 for times printed to 6 decimals),
// or 0 once a value has more decimals than a double resolves (a float32 or float64 value that
// was never rounded to decimals). Time stamps rounded to that unit from equally spaced times
// have steps that differ by at most one unit, so a step may differ from another by that much.
//
// Example:
//   TimePrecision p;
//   p.see(0.000977);
//   p.unit();  // 1e-6
class TimePrecision {
 public:
  // Most values need no more decimals than those before them: one test.
  void see(double t) {
    if (!binary_ && !whole(t * scale_)) see_more_decimals(t);
  }
  double unit() const { return unit_; }
  // Whether see() would change nothing for any of the four values t[0..3]: each of them needs no
  // more decimals than those seen, as `whole` finds it (the same operations, four at a time).
  bool sees_nothing_new(const double* t) const {
    if (binary_) return true;
    using Four = double __attribute__((vector_size(4 * sizeof(double))));
    constexpr double kLimit = 4503599627370496.0;
    constexpr double kRounding = 4 * std::numeric_limits<double>::epsilon();
    Four x;
    std::memcpy(&x, t, sizeof x);
    x *= scale_;
    const Four a = x < 0 ? -x : x;
    const Four nearest = (a + kLimit) - kLimit;
    const Four off = a - nearest;
    const Four one = {1, 1, 1, 1};
    const auto held = (a < kLimit) & ((off < 0 ? -off : off) <= kRounding * (a > one ? a : one));
    return held[0] && held[1] && held[2] && held[3];
  }

 private:
  // Whether x, a value scaled by a power of ten, is a whole number up to the rounding of the
  // value and of the scaling (a few units in the last place of a double).
  static bool whole(double x) {
    constexpr double kLimit = 4503599627370496.0;  // 2^52: above it every double is whole
    constexpr double kRounding = 4 * std::numeric_limits<double>::epsilon();
    const double a = std::abs(x);
    // a to the nearest whole number as std::nearbyint rounds it, without a library call for
    // every time stamp: in [2^52, 2^53) the doubles are the whole numbers.
    const double nearest = (a + kLimit) - kLimit;
    return a < kLimit && std::abs(a - nearest) <= kRounding * std::max(a, 1.0);
  }
  void see_more_decimals(double t);

  int decimals_ = 0;
  double scale_ = 1;  // 10^decimals_
  double unit_ = 1;   // 1 / scale_, or 0 once binary_
  bool binary_ = false;
};

}  // namespace momentid::data
