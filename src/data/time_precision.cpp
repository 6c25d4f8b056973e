#include "data/time_precision.hpp"

#include <cmath>

namespace momentid::data {
namespace {

// Beyond 17 decimals no double is written exactly in fewer.
constexpr int kMaxDecimals = 17;

}  // namespace

void TimePrecision::see_more_decimals(double t) {
  for (int d = decimals_ + 1; d <= kMaxDecimals; ++d) {
    const double scale = std::pow(10.0, d);
    if (whole(t * scale)) {
      decimals_ = d;
      scale_ = scale;
      unit_ = 1 / scale;
      return;
    }
  }
  binary_ = true;
  unit_ = 0;
}

}  // namespace momentid::data
