#include "common/number.hpp"

#include <cmath>
#include <cstdio>

namespace momentid {

std::string number(double x, const char* format) {
  if (std::isnan(x)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

}  // namespace momentid
