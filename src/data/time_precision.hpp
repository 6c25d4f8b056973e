#pragma once

#include <limits>

#include "moments/kernel.hpp"

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
  // more decimals than those seen (`whole`, four lanes at a time).
  bool sees_nothing_new(const double* t) const {
    if (binary_) return true;
    const auto held = whole(load_four(t) * scale_);
    return held[0] && held[1] && held[2] && held[3];
  }

  // |x| and the larger of a and b, for a double and for each lane of a Four (kernel.hpp) alike
  // (std::abs and std::max, but for the sign of a zero).
  template <class T>
  static T magnitude(T x) {
    return x < 0 ? -x : x;
  }
  template <class T>
  static T larger(T a, T b) {
    return a < b ? b : a;
  }

 private:
  // Whether x, a value scaled by a power of ten, is a whole number up to the rounding of the
  // value and of the scaling (a few units in the last place of a double); for Four, of each lane.
  template <class T>
  static auto whole(T x) -> decltype(x < 1.0) {
    constexpr double kLimit = 4503599627370496.0;  // 2^52: above it every double is whole
    constexpr double kRounding = 4 * std::numeric_limits<double>::epsilon();
    const T a = magnitude(x);
    // a to the nearest whole number as std::nearbyint rounds it, without a library call for
    // every time stamp: in [2^52, 2^53) the doubles are the whole numbers.
    const T nearest = (a + kLimit) - kLimit;
    const T one = T{} + 1.0;
    return (a < kLimit) & (magnitude(a - nearest) <= kRounding * larger(a, one));
  }
  void see_more_decimals(double t);

  int decimals_ = 0;
  double scale_ = 1;  // 10^decimals_
  double unit_ = 1;   // 1 / scale_, or 0 once binary_
  bool binary_ = false;
};

}  // namespace momentid::data
