#pragma once
// The lines before the data rows of a text data file (and of a binary file's header text), and
// the columns a request takes from them.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "data/lines.hpp"
#include "momentid/reader.hpp"

namespace momentid::data {

// What the lines before the data say: metadata and the column names.
struct Header {
  DataMetadata metadata;
  std::optional<double> metadata_dt;
  // Where metadata_dt comes from, as messages name it: "dt=0.01 in the metadata".
  std::string metadata_dt_source;
  std::vector<std::string> names;
  std::vector<std::size_t> name_columns;  // byte column of each name, from 1
  char separator = ',';                   // ',', ';' or ' ' for runs of blanks and tabs
  long long line = 0;
  std::string text;
  // How messages introduce the names: "the header has", "the file has the variables", ...
  std::string listing = "the header has";
  // What one of them is called: "column", "variable", "dataset".
  std::string item = "column";
};

// Reads the metadata and comment lines and the header row (`binary`: of a binary file's header
// text).
Header read_header(const std::string& path, LineReader& lines, bool binary = false);

// Which field of a row goes where.
struct ColumnMap {
  std::vector<int> output;   // per field: the index in ColumnRequest::names it fills, or -1
  std::vector<char> needed;  // per field: read as a number (requested, `t` or `run`)
  std::vector<std::pair<std::size_t, std::size_t>> copies;  // (to, from): one column, two names
  int time = -1;
  int run = -1;
};

// Whether a column name reads as a time: `t` or `time` in any case, optionally followed by a
// unit in brackets or parentheses (`t [s]`, `Time (s)`).
bool is_time_name(std::string_view name);

// The fields that fill `request`. Throws DataError, located in the header row, for a missing
// column or a needed one that appears twice.
ColumnMap map_columns(const std::string& path, const Header& header, const ColumnRequest& request);

}  // namespace momentid::data
