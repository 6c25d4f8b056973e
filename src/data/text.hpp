#pragma once
// What the readers of text and binary data files share: a few views on text, numbers as the
// files write them, and errors located at a line and column.

#include <fast_float/fast_float.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "momentid/error.hpp"

namespace momentid::data {

// An error shows at most this much of a field, and of a line at least this much.
inline constexpr std::size_t kShownFieldBytes = 40;
inline constexpr std::size_t kShownLineBytes = 200;

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

// Inline: the readers call these for every field.
inline bool is_blank(char c) { return c == ' ' || c == '\t'; }

inline const char* skip_blanks(const char* p, const char* end) {
  while (p != end && is_blank(*p)) ++p;
  return p;
}

inline bool is_blank_line(std::string_view line) {
  return std::all_of(line.begin(), line.end(), is_blank);
}

std::string_view trim(std::string_view s);

// Parses a number at the start of [p, end) (fast_float, plus an optional leading '+'). Returns
// the end of the number, or nullptr when there is none. Non-finite values are returned as such.
inline const char* parse_number(const char* p, const char* end, double& value, char decimal = '.') {
  if (p != end && *p == '+') {
    ++p;
    if (p == end || *p == '+' || *p == '-') return nullptr;
  }
  const fast_float::from_chars_result result = fast_float::from_chars_advanced(
      p, end, value, fast_float::parse_options{fast_float::chars_format::general, decimal});
  if (result.ec == std::errc::result_out_of_range) {
    value = std::numeric_limits<double>::infinity();
  } else if (result.ec != std::errc()) {
    return nullptr;
  }
  return result.ptr;
}
// `text` is exactly one number (finite or not).
bool is_number(std::string_view text, double& value);

// `a` and `b` with the fewest significant digits (at least 6) that tell them apart: steps are
// differences of rounded times, so their shortest forms show noise nobody wrote.
std::pair<std::string, std::string> distinguished(double a, double b);

// A field as an error message shows it: quoted, at most kShownFieldBytes of it.
std::string quoted_field(std::string_view field);
// "1 row", "2 rows".
std::string plural(std::size_t count, const std::string& noun);
int clamp_to_int(long long n);

// A place in a text line. Very long lines are cut after kShownLineBytes, or a little after the
// column when it lies further: the caret must still fall under the column in the line shown.
SourceLocation text_location(const std::string& path, long long line, std::size_t column,
                             std::string_view text);

[[noreturn]] void fail(SourceLocation where, const std::string& message);

// The position in `file` as a fraction of its size; nullopt for a pipe or an empty file.
std::optional<double> file_fraction(std::FILE* file);
// The size of a regular file, or nullopt.
std::optional<std::uint64_t> file_size(std::FILE* file);

// Reads up to `size` bytes, fewer only at the end of the file.
std::size_t read_fully(std::FILE* file, const std::string& path, void* into, std::size_t size);

}  // namespace momentid::data
