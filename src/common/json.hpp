#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace momentid {

// `s` as a JSON string literal, quotes included: `"`, `\` and control characters escaped.
std::string json_string(std::string_view s);
// `items` as a JSON array of strings: `["a", "b"]`.
std::string json_strings(const std::vector<std::string>& items);
// `x` as a JSON number with 17 significant digits, or `null` when it is not finite.
std::string json_number(double x);

}  // namespace momentid
