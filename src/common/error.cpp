#include "common/error.hpp"

#include <algorithm>

namespace momentid {

std::string render_with_caret(const LocatedError& error) {
  const SourceLocation& w = error.location();
  std::string out = error.what();
  if (w.text.empty()) return out;
  // Long lines are shown as a window around the column, so that the caret stays in view.
  constexpr std::size_t kBefore = 70, kAfter = 50;
  const std::size_t column = static_cast<std::size_t>(std::max(w.column, 1)) - 1;
  const std::size_t begin = column > kBefore ? column - kBefore : 0;
  const std::size_t end = std::min(w.text.size(), column + kAfter);
  const std::string lead = begin > 0 ? "..." : "";
  const std::string shown =
      lead + w.text.substr(begin, end - begin) + (end < w.text.size() ? "..." : "");
  const std::string number = std::to_string(w.line);
  out += "\n " + number + " | " + shown + "\n " + std::string(number.size(), ' ') + " | " +
         std::string(lead.size(), ' ');
  for (std::size_t i = begin; i < column && i < w.text.size(); ++i) {
    out += w.text[i] == '\t' ? '\t' : ' ';
  }
  return out + "^";
}

}  // namespace momentid
