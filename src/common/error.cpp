#include "common/error.hpp"

namespace momentid {

std::string render_with_caret(const LocatedError& error) {
  const SourceLocation& w = error.location();
  std::string out = error.what();
  if (w.text.empty()) return out;
  const std::string number = std::to_string(w.line);
  out += "\n " + number + " | " + w.text + "\n " + std::string(number.size(), ' ') + " | ";
  for (int i = 1; i < w.column && i <= static_cast<int>(w.text.size()); ++i) {
    out += w.text[static_cast<std::size_t>(i - 1)] == '\t' ? '\t' : ' ';
  }
  return out + "^";
}

}  // namespace momentid
