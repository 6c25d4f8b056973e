#include "data/format.hpp"

#include <cmath>

#include "data/text.hpp"

namespace momentid::data {

DataMetadata::Line read_metadata_line(const std::string& path, long long line_number,
                                      std::string_view line, std::size_t pairs) {
  DataMetadata::Line out;
  std::size_t at = pairs;
  for (;;) {
    while (at < line.size() && is_blank(line[at])) ++at;
    if (at == line.size()) return out;
    std::size_t token_end = at;
    while (token_end < line.size() && !is_blank(line[token_end])) ++token_end;
    const std::string_view token = line.substr(at, token_end - at);
    const std::size_t equals = token.find('=');
    if (equals == std::string_view::npos || equals == 0) {
      fail(text_location(path, line_number, at + 1, line),
           "metadata: expected key=value, found " + quoted_field(token));
    }
    const std::string key(token.substr(0, equals));
    const std::string_view value = token.substr(equals + 1);
    double dt = 0;
    if (key == "dt" && (!is_number(value, dt) || !std::isfinite(dt) || dt <= 0)) {
      fail(text_location(path, line_number, at + equals + 2, line),
           "metadata dt: expected a positive number, found " +
               (value.empty() ? std::string("nothing") : quoted_field(value)));
    }
    out.emplace_back(key, value);
    at = token_end;
  }
}

std::string header_text(const DataMetadata& metadata, const std::vector<std::string>& columns) {
  std::string out = metadata.text();
  for (std::size_t c = 0; c < columns.size(); ++c) {
    // A name holding the separator (`a[:, 0]`) is quoted.
    const bool quote = columns[c].find(',') != std::string::npos;
    out += (c ? "," : "") + (quote ? "\"" + columns[c] + "\"" : columns[c]);
  }
  return out + "\n";
}

}  // namespace momentid::data
