#include "data/text.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

namespace momentid::data {

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

bool is_number(std::string_view text, double& value) {
  const char* end = text.data() + text.size();
  return !text.empty() && parse_number(text.data(), end, value) == end;
}

std::pair<std::string, std::string> distinguished(double a, double b) {
  std::array<char, 40> buffer_a, buffer_b;
  std::string text_a, text_b;
  for (int precision = 6; precision <= 17; ++precision) {
    const auto end_a = std::to_chars(buffer_a.data(), buffer_a.data() + buffer_a.size(), a,
                                     std::chars_format::general, precision);
    const auto end_b = std::to_chars(buffer_b.data(), buffer_b.data() + buffer_b.size(), b,
                                     std::chars_format::general, precision);
    text_a.assign(buffer_a.data(), end_a.ptr);
    text_b.assign(buffer_b.data(), end_b.ptr);
    if (text_a != text_b) break;
  }
  return {text_a, text_b};
}

std::string quoted_field(std::string_view field) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, wrongly) about "'" + a temporary.
  std::string out = "'";
  if (field.size() <= kShownFieldBytes) {
    out += field;
    out += "'";
    return out;
  }
  std::size_t cut = kShownFieldBytes;
  // Do not cut a UTF-8 sequence: back up to the start of the character.
  while (cut > 0 && (static_cast<unsigned char>(field[cut]) & 0xC0) == 0x80) --cut;
  out += field.substr(0, cut);
  out += "...'";
  return out;
}

std::string plural(std::size_t count, const std::string& noun) {
  return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

int clamp_to_int(long long n) {
  return static_cast<int>(std::min<long long>(n, std::numeric_limits<int>::max()));
}

SourceLocation text_location(const std::string& path, long long line, std::size_t column,
                             std::string_view text) {
  const std::size_t keep = std::max(kShownLineBytes, column - 1 + kShownFieldBytes);
  std::string shown(text.substr(0, keep));
  if (text.size() > keep) shown += "...";
  return {path, clamp_to_int(line), clamp_to_int(static_cast<long long>(column)), shown};
}

[[noreturn]] void fail(SourceLocation where, const std::string& message) {
  throw DataError(std::move(where), message);
}

std::optional<std::uint64_t> file_size(std::FILE* file) {
  struct stat info;
  if (fstat(fileno(file), &info) != 0 || !S_ISREG(info.st_mode)) return std::nullopt;
  return static_cast<std::uint64_t>(info.st_size);
}

std::optional<double> file_fraction(std::FILE* file) {
  struct stat info;
  if (fstat(fileno(file), &info) != 0 || !S_ISREG(info.st_mode) || info.st_size <= 0) {
    return std::nullopt;
  }
  const long at = std::ftell(file);
  if (at < 0) return std::nullopt;
  return std::min(1.0, static_cast<double>(at) / static_cast<double>(info.st_size));
}

std::size_t read_fully(std::FILE* file, const std::string& path, void* into, std::size_t size) {
  std::size_t got = 0;
  while (got < size) {
    const std::size_t n = std::fread(static_cast<char*>(into) + got, 1, size - got, file);
    if (n == 0) {
      if (std::ferror(file)) {
        throw Error(path + ": cannot read the data file: " + std::strerror(errno));
      }
      break;
    }
    got += n;
  }
  return got;
}

}  // namespace momentid::data
