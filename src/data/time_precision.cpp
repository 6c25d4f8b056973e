#include "data/time_precision.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace momentid::data {
namespace {

// Beyond 17 decimals no double is written exactly in fewer.
constexpr int kMaxDecimals = 17;

// Whether x, a value scaled by a power of ten, is a whole number up to the rounding of the value
// and of the scaling (a few units in the last place of a double).
bool whole(double x) {
  constexpr double kLimit = 4503599627370496.0;  // 2^52: above it every double is whole
  constexpr double kRounding = 4 * std::numeric_limits<double>::epsilon();
  return std::abs(x) < kLimit &&
         std::abs(x - std::nearbyint(x)) <= kRounding * std::max(std::abs(x), 1.0);
}

}  // namespace

void TimePrecision::see(double t) {
  // Most values need no more decimals than those before them: one test.
  if (binary_ || whole(t * scale_)) return;
  for (int d = decimals_ + 1; d <= kMaxDecimals; ++d) {
    const double scale = std::pow(10.0, d);
    if (whole(t * scale)) {
      decimals_ = d;
      scale_ = scale;
      return;
    }
  }
  binary_ = true;
}

double TimePrecision::unit() const { return binary_ ? 0 : 1 / scale_; }

}  // namespace momentid::data
