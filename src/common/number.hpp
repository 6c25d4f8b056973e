#pragma once

#include <string>

namespace momentid {

// `x` as the printf conversion `format` (one conversion of a double, such as "%.3g") prints it,
// or `n/a` when it is NaN: the numbers of the text reports.
std::string number(double x, const char* format = "%.6g");

}  // namespace momentid
