#include "common/decimal.hpp"

#include <array>
#include <charconv>

namespace momentid {

std::string shortest_decimal(double x) {
  std::array<char, 32> buffer;
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), x);
  return std::string(buffer.data(), result.ptr);
}

}  // namespace momentid
