#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace momentid {

// `s` as a JSON string literal, quotes included: `"`, `\` and control characters escaped.
std::string json_string(std::string_view s);
// `x` as a JSON number with 17 significant digits, or `null` when it is not finite.
std::string json_number(double x);

// `x` as a JSON value: the number, or null when it is not finite (JSON has neither NaN nor
// infinity), so that a value reads back from its text as it was.
nlohmann::ordered_json json_value(double x);
// `values` as a JSON array of json_value(x).
nlohmann::ordered_json json_value(const std::vector<double>& values);
// Rows of numbers, e.g. a correlation matrix, as an array of arrays.
nlohmann::ordered_json json_value(const std::vector<std::vector<double>>& rows);

// The text of a result's value (format_json): indented by two spaces, each number in the
// shortest form that reads back to the same double, a byte that is not valid UTF-8 replaced by
// U+FFFD so that the text stays JSON, and a final newline.
std::string json_text(const nlohmann::ordered_json& value);

}  // namespace momentid
