#pragma once

#include <limits>
#include <sstream>
#include <string>

namespace momentid {

// What the solver reports where a number is not determined (a parameter the data cannot
// separate, an error without batches).
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A number in a message or a warning: four significant digits.
inline std::string format_number(double x) {
  std::ostringstream out;
  out.precision(4);
  out << x;
  return out.str();
}

}  // namespace momentid
