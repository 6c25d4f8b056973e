#pragma once

#include <string>

namespace momentid {

// The shortest decimal text that reads back as exactly `x`.
std::string shortest_decimal(double x);

}  // namespace momentid
