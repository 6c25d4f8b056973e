#include "cli/commands.hpp"
#include "momentid/error.hpp"

namespace momentid::cli {

std::map<std::string, std::string> column_map(const std::vector<std::string>& entries) {
  std::map<std::string, std::string> out;
  for (const std::string& e : entries) {
    const std::size_t eq = e.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == e.size()) {
      throw UsageError("--columns: expected NAME=COLUMN, found '" + e + "'");
    }
    out[e.substr(0, eq)] = e.substr(eq + 1);
  }
  return out;
}

std::optional<InputHold> hold_option(const std::string& text) {
  if (text == "zoh") return InputHold::kZeroOrderHold;
  if (text == "sample") return InputHold::kSample;
  return std::nullopt;
}

}  // namespace momentid::cli
