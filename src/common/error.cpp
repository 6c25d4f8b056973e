#include "momentid/error.hpp"

#include <algorithm>
#include <string_view>

namespace momentid {

namespace {

// Around a field's name in a message: control characters, which no message has otherwise.
constexpr char kMentionBegin = '\x01', kMentionEnd = '\x02';

std::string spelled(const std::string& option, const std::string& message,
                    const std::function<std::string(const std::string&)>& spell) {
  std::string out = option.empty() ? "" : spell(option) + ": ";
  for (std::size_t i = 0; i < message.size(); ++i) {
    const std::size_t end = message.find(kMentionEnd, i);
    if (message[i] != kMentionBegin || end == std::string::npos) {
      out += message[i];
      continue;
    }
    out += spell(message.substr(i + 1, end - i - 1));
    i = end;
  }
  return out;
}

std::string as_field(const std::string& field) { return field; }

}  // namespace

UsageError::UsageError(std::string option, std::string message)
    : Error(spelled(option, message, as_field)),
      option_(std::move(option)),
      message_(std::move(message)) {}

std::string UsageError::text(const std::function<std::string(const std::string&)>& spell) const {
  return spelled(option_, message_, spell);
}

std::string UsageError::mention(std::string_view field) {
  return kMentionBegin + std::string(field) + kMentionEnd;
}

namespace {

std::string place(const SourceLocation& where) {
  return where.file + ":" + std::to_string(where.line) + ":" + std::to_string(where.column) + ": ";
}

}  // namespace

LocatedError::LocatedError(SourceLocation where, const std::string& message)
    : Error(place(where) + spelled("", message, as_field)),
      where_(std::move(where)),
      message_(message) {}

std::string LocatedError::text(const std::function<std::string(const std::string&)>& spell) const {
  return place(where_) + spelled("", message_, spell);
}

namespace {

// A character that reorders the text shown around it (U+061C, U+200E, U+200F, U+202A..U+202E,
// U+2066..U+2069): a message that echoes one could show other text than it holds.
bool bidirectional_control(std::string_view utf8) {
  static constexpr std::string_view kControls[] = {"\xD8\x9C",     "\xE2\x80\x8E", "\xE2\x80\x8F",
                                                   "\xE2\x80\xAA", "\xE2\x80\xAB", "\xE2\x80\xAC",
                                                   "\xE2\x80\xAD", "\xE2\x80\xAE", "\xE2\x81\xA6",
                                                   "\xE2\x81\xA7", "\xE2\x81\xA8", "\xE2\x81\xA9"};
  return std::find(std::begin(kControls), std::end(kControls), utf8) != std::end(kControls);
}

}  // namespace

std::string printable(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte < 0x80) {
      out += (byte < 0x20 && byte != '\t' && byte != '\n') || byte == 0x7f ? '?' : text[i];
      continue;
    }
    // Keep valid UTF-8 sequences, replace anything else.
    const std::size_t n = (byte >> 5) == 6 ? 2 : (byte >> 4) == 14 ? 3 : (byte >> 3) == 30 ? 4 : 0;
    bool valid = n > 0 && i + n <= text.size();
    for (std::size_t k = 1; valid && k < n; ++k) {
      valid = (static_cast<unsigned char>(text[i + k]) >> 6) == 2;
    }
    if (valid && !bidirectional_control(text.substr(i, n))) {
      out.append(text.substr(i, n));
      i += n - 1;
    } else {
      out += '?';
      if (valid) i += n - 1;
    }
  }
  return out;
}

std::string render_with_caret(const LocatedError& error,
                              const std::function<std::string(const std::string&)>& spell) {
  const SourceLocation& w = error.location();
  std::string out = printable(spell ? error.text(spell) : std::string(error.what()));
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
  out += "\n " + number + " | " + printable(shown) + "\n " + std::string(number.size(), ' ') +
         " | " + std::string(lead.size(), ' ');
  for (std::size_t i = begin; i < column && i < w.text.size(); ++i) {
    out += w.text[i] == '\t' ? '\t' : ' ';
  }
  return out + "^";
}

}  // namespace momentid
