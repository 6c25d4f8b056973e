#include "model/syntax.hpp"

#include <stdexcept>

#include "momentid/model.hpp"

namespace momentid {

std::string line_of(std::string_view source, std::size_t line) {
  std::size_t begin = 0;
  for (std::size_t n = 1; n < line && begin != std::string_view::npos; ++n) {
    begin = source.find('\n', begin);
    if (begin != std::string_view::npos) ++begin;
  }
  if (begin == std::string_view::npos || begin > source.size()) return "";
  std::size_t end = source.find('\n', begin);
  std::string text(source.substr(begin, end == std::string_view::npos ? end : end - begin));
  if (!text.empty() && text.back() == '\r') text.pop_back();
  return text;
}

SourceLocation Source::where(const SyntaxNode& node) const {
  return {file_, static_cast<int>(node.line), static_cast<int>(node.column),
          line_of(text_, node.line)};
}

SourceLocation Source::start() const { return {file_, 1, 1, line_of(text_, 1)}; }

void Source::fail(const SyntaxNode& node, const std::string& message) const {
  throw ModelError(where(node), message);
}

GiNaC::numeric Source::number(const SyntaxNode& node) const {
  try {
    return parse_exact_number(node.text);
  } catch (const std::out_of_range& e) {
    fail(node, e.what());
  }
}

}  // namespace momentid
