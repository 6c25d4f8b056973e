// Reads CSV and binary data files (data.hpp) in chunks, checking every field it delivers.
//
// Choices the header leaves open, made here:
// - Blank lines (empty, or only blanks and tabs) are ignored wherever they are: before the
//   header, among the data rows and at the end of the file.
// - A `#` line after the header is a data row like any other (and so an error).
// - Comma- and semicolon-separated fields may carry blanks around them; an empty header name
//   (e.g. the index column pandas writes) names a column that cannot be requested.
// - A `run` value must be an integer, written with or without a zero fraction (`3` or `3.0`).
// - Columns count bytes from the start of the line; on the first line they count from after a
//   UTF-8 byte order mark, so that they match the line text the error carries.
// - In a binary file, errors in the header text are located by the line and byte column of that
//   text, errors in the rows by the row number (from 1) and the column number (from 1).

#include <fast_float/fast_float.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "momentid/reader.hpp"

namespace momentid {

std::optional<std::string> DataMetadata::get(const std::string& key) const {
  const auto found = values.find(key);
  if (found == values.end()) return std::nullopt;
  return found->second;
}

namespace {

constexpr std::size_t kChunkBytes = std::size_t{1} << 20;
// A longer "line" means the file is not a text data file; stop before memory runs out.
constexpr std::size_t kMaxLineBytes = std::size_t{256} << 20;
constexpr std::uint32_t kMaxBinaryHeaderBytes = std::uint32_t{16} << 20;
constexpr std::string_view kMagic = "MOMNTID1";
constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";
constexpr std::string_view kMetadataTag = "momentid:";
constexpr std::size_t kShownFieldBytes = 40;
constexpr std::size_t kShownLineBytes = 200;
// Relative tolerance of a time step: far above the rounding of times written with ten or more
// significant digits, far below a missing sample or a changed step.
constexpr double kStepTolerance = 1e-6;
// Steps are differences of times: rounding of t itself adds an error proportional to |t|.
constexpr double kTimeRounding = 1e-9;

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

bool is_blank(char c) { return c == ' ' || c == '\t'; }

const char* skip_blanks(const char* p, const char* end) {
  while (p != end && is_blank(*p)) ++p;
  return p;
}

bool is_blank_line(std::string_view line) {
  return std::all_of(line.begin(), line.end(), is_blank);
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

// Parses a number at the start of [p, end) (fast_float, plus an optional leading '+'). Returns
// the end of the number, or nullptr when there is none. Non-finite values are returned as such.
const char* parse_number(const char* p, const char* end, double& value) {
  if (p != end && *p == '+') {
    ++p;
    if (p == end || *p == '+' || *p == '-') return nullptr;
  }
  const fast_float::from_chars_result result = fast_float::from_chars(p, end, value);
  if (result.ec == std::errc::result_out_of_range) {
    value = std::numeric_limits<double>::infinity();
  } else if (result.ec != std::errc()) {
    return nullptr;
  }
  return result.ptr;
}

// `text` is exactly one number (finite or not).
bool is_number(std::string_view text, double& value) {
  const char* end = text.data() + text.size();
  return !text.empty() && parse_number(text.data(), end, value) == end;
}

// The shortest decimal that reads back as `value`.
std::string shortest(double value) {
  std::array<char, 32> buffer;
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

// `a` and `b` with the fewest significant digits (at least 6) that tell them apart: steps are
// differences of rounded times, so their shortest forms show noise nobody wrote.
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

// A field as an error message shows it: quoted, at most kShownFieldBytes of it.
std::string quoted_field(std::string_view field) {
  if (field.size() <= kShownFieldBytes) return "'" + std::string(field) + "'";
  std::size_t cut = kShownFieldBytes;
  // Do not cut a UTF-8 sequence: back up to the start of the character.
  while (cut > 0 && (static_cast<unsigned char>(field[cut]) & 0xC0) == 0x80) --cut;
  return "'" + std::string(field.substr(0, cut)) + "...'";
}

std::string plural(std::size_t count, const std::string& noun) {
  return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

int clamp_to_int(long long n) {
  return static_cast<int>(std::min<long long>(n, std::numeric_limits<int>::max()));
}

// A place in a text line. Very long lines are cut after kShownLineBytes, or a little after the
// column when it lies further: the caret must still fall under the column in the line shown.
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

// Delivers the lines of a file, or of a text in memory, one at a time, without their line
// break (LF or CR LF). A file is read in chunks of kChunkBytes; a line is a view into the
// current chunk, valid until the next call.
class LineReader {
 public:
  // Reads `file`, whose first bytes, already read, are `start`.
  LineReader(std::FILE* file, std::string path, std::string_view start)
      : file_(file), path_(std::move(path)), buffer_(std::max(kChunkBytes, start.size())) {
    std::memcpy(buffer_.data(), start.data(), start.size());
    end_ = start.size();
  }
  // Reads the lines of `text`.
  explicit LineReader(std::string_view text) : buffer_(text.begin(), text.end()) {
    end_ = buffer_.size();
    at_end_ = true;
  }

  bool next(std::string_view& line) {
    for (;;) {
      const char* const start = buffer_.data() + begin_;
      const std::size_t available = end_ - begin_;
      const void* const newline = std::memchr(start, '\n', available);
      if (newline != nullptr) {
        const std::size_t length = static_cast<const char*>(newline) - start;
        begin_ += length + 1;
        line = deliver(start, length);
        return true;
      }
      if (at_end_) {
        if (available == 0) return false;
        begin_ = end_;
        line = deliver(start, available);
        return true;
      }
      refill();
    }
  }

  // The line the last call of next() delivered, from 1.
  long long line_number() const { return line_number_; }

 private:
  std::string_view deliver(const char* start, std::size_t length) {
    ++line_number_;
    if (length > 0 && start[length - 1] == '\r') --length;
    return {start, length};
  }

  // Keeps the unfinished line, at the front of the buffer, and appends the next chunk.
  void refill() {
    const std::size_t kept = end_ - begin_;
    if (kept == buffer_.size()) {
      if (buffer_.size() >= kMaxLineBytes) {
        fail({path_, clamp_to_int(line_number_ + 1), 1, ""},
             "line longer than " + std::to_string(kMaxLineBytes >> 20) +
                 " MiB: this is not a text data file");
      }
      buffer_.resize(buffer_.size() * 2);
    }
    std::memmove(buffer_.data(), buffer_.data() + begin_, kept);
    begin_ = 0;
    end_ = kept;
    const std::size_t got = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
    if (got == 0) {
      if (std::ferror(file_)) {
        throw Error(path_ + ": cannot read the data file: " + std::strerror(errno));
      }
      at_end_ = true;
    }
    end_ += got;
  }

  std::FILE* file_ = nullptr;
  std::string path_;
  std::vector<char> buffer_;
  std::size_t begin_ = 0, end_ = 0;
  bool at_end_ = false;
  long long line_number_ = 0;
};

// What the lines before the data say: metadata and the column names.
struct Header {
  DataMetadata metadata;
  std::optional<double> metadata_dt;
  std::string metadata_dt_text;
  std::vector<std::string> names;
  std::vector<std::size_t> name_columns;  // byte column of each name, from 1
  char separator = ',';                   // ',', ';' or ' ' for runs of blanks and tabs
  long long line = 0;
  std::string text;
};

// Reads the `key=value` pairs of a `# momentid:` line, whose pairs start at `pairs`.
void read_metadata(const std::string& path, long long line_number, std::string_view line,
                   std::size_t pairs, Header& header) {
  std::size_t at = pairs;
  for (;;) {
    while (at < line.size() && is_blank(line[at])) ++at;
    if (at == line.size()) return;
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
    if (key == "dt") {
      double dt = 0;
      if (!is_number(value, dt) || !std::isfinite(dt) || dt <= 0) {
        fail(text_location(path, line_number, at + equals + 2, line),
             "metadata dt: expected a positive number, found " +
                 (value.empty() ? std::string("nothing") : quoted_field(value)));
      }
      header.metadata_dt = dt;
      header.metadata_dt_text = value;
    }
    header.metadata.values[key] = value;
    at = token_end;
  }
}

// Splits the header row into names, taking the separator from it.
void read_names(const std::string& path, std::string_view line, Header& header) {
  header.separator = line.find(',') != std::string_view::npos   ? ','
                     : line.find(';') != std::string_view::npos ? ';'
                                                                : ' ';
  auto add = [&](std::size_t begin, std::size_t end) {
    std::string_view name = line.substr(begin, end - begin);
    const std::size_t leading = std::min(name.find_first_not_of(" \t"), name.size());
    name = trim(name);
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') {
      name = name.substr(1, name.size() - 2);
    }
    header.names.emplace_back(name);
    header.name_columns.push_back(begin + leading + 1);
  };
  if (header.separator == ' ') {
    std::size_t at = 0;
    for (;;) {
      while (at < line.size() && is_blank(line[at])) ++at;
      if (at == line.size()) break;
      std::size_t end = at;
      while (end < line.size() && !is_blank(line[end])) ++end;
      add(at, end);
      at = end;
    }
  } else {
    std::size_t begin = 0;
    for (;;) {
      const std::size_t end = std::min(line.find(header.separator, begin), line.size());
      add(begin, end);
      if (end == line.size()) break;
      begin = end + 1;
    }
  }
  const bool all_numbers = std::all_of(header.names.begin(), header.names.end(), [](auto& n) {
    double value;
    return is_number(n, value);
  });
  if (all_numbers) {
    fail(text_location(path, header.line, 1, line),
         "expected a header row naming the columns, found a row of numbers");
  }
}

// Reads the metadata and comment lines and the header row (`binary`: of a binary file's header
// text).
Header read_header(const std::string& path, LineReader& lines, bool binary = false) {
  Header header;
  std::string_view line;
  std::string first_line;
  bool empty = true;
  while (lines.next(line)) {
    const long long number = lines.line_number();
    if (number == 1) {
      if (line.starts_with(kByteOrderMark)) line.remove_prefix(kByteOrderMark.size());
      first_line = line;
    }
    if (!line.empty() || number > 1) empty = false;
    const std::size_t start = line.find_first_not_of(" \t");
    if (start == std::string_view::npos) continue;
    if (line[start] == '#') {
      const std::size_t tag = line.find_first_not_of(" \t", start + 1);
      if (tag != std::string_view::npos && line.substr(tag).starts_with(kMetadataTag)) {
        read_metadata(path, number, line, tag + kMetadataTag.size(), header);
      }
      continue;
    }
    header.line = number;
    header.text = line;
    read_names(path, line, header);
    return header;
  }
  fail(text_location(path, 1, 1, first_line),
       empty && !binary ? "the file is empty: expected a header row naming the columns"
                        : "expected a header row naming the columns");
}

// Which field of a row goes where.
struct ColumnMap {
  std::vector<int> output;   // per field: the index in ColumnRequest::names it fills, or -1
  std::vector<char> needed;  // per field: read as a number (requested, `t` or `run`)
  std::vector<std::pair<std::size_t, std::size_t>> copies;  // (to, from): one column, two names
  int time = -1;
  int run = -1;
};

ColumnMap map_columns(const std::string& path, const Header& header, const ColumnRequest& request) {
  const auto location = [&](std::size_t column) {
    return text_location(path, header.line, column, header.text);
  };
  // The header's names for messages: the first twelve, each cut at 40 characters.
  std::string listed;
  for (std::size_t i = 0; i < header.names.size() && i < 12; ++i) {
    const std::string& name = header.names[i];
    listed += (listed.empty() ? "" : ", ") + name.substr(0, 40) + (name.size() > 40 ? "..." : "");
  }
  if (header.names.size() > 12) {
    listed += " and " + std::to_string(header.names.size() - 12) + " more";
  }

  std::vector<std::string> file_names;
  for (const std::string& name : request.names) {
    const auto renamed = request.rename.find(name);
    file_names.push_back(renamed == request.rename.end() ? name : renamed->second);
  }
  const auto matters = [&](const std::string& name) {
    return name == "t" || name == "run" ||
           std::find(file_names.begin(), file_names.end(), name) != file_names.end();
  };

  ColumnMap map;
  map.output.assign(header.names.size(), -1);
  map.needed.assign(header.names.size(), 0);
  std::map<std::string_view, std::size_t> first;
  for (std::size_t i = 0; i < header.names.size(); ++i) {
    const std::string& name = header.names[i];
    const auto [seen, inserted] = first.emplace(name, i);
    if (!inserted && matters(name)) {
      fail(location(header.name_columns[i]),
           "column '" + name + "' appears twice in the header (first at column " +
               std::to_string(header.name_columns[seen->second]) + ")");
    }
  }
  if (const auto t = first.find("t"); t != first.end()) map.time = static_cast<int>(t->second);
  if (const auto r = first.find("run"); r != first.end()) map.run = static_cast<int>(r->second);
  if (map.time >= 0) map.needed[map.time] = 1;
  if (map.run >= 0) map.needed[map.run] = 1;

  for (std::size_t k = 0; k < request.names.size(); ++k) {
    const auto found = first.find(file_names[k]);
    if (found == first.end()) {
      const std::string& name = request.names[k];
      fail(location(1), "missing column '" + file_names[k] + "'" +
                            (file_names[k] == name ? "" : " for '" + name + "'") +
                            " (the header has: " + listed + ")");
    }
    const std::size_t field = found->second;
    if (map.output[field] < 0) {
      map.output[field] = static_cast<int>(k);
      map.needed[field] = 1;
    } else {
      map.copies.emplace_back(k, static_cast<std::size_t>(map.output[field]));
    }
  }
  return map;
}

// A run number must be an integer that fits a long.
bool to_run(double value, long& run) {
  constexpr double kLimit = 9.0e18;
  if (!(std::abs(value) < kLimit) || value != std::trunc(value)) return false;
  run = static_cast<long>(value);
  return true;
}

// The time and run of a row.
struct RowKeys {
  double t = 0;
  long run = 0;
};

// The reading both layouts share: blocks, runs and the time-step checks. A layout delivers rows
// through read_row() and says where a field is for errors.
class StreamReader : public DataReader {
 public:
  const DataMetadata& metadata() const override { return header_.metadata; }

  const std::vector<std::string>& columns() const override { return header_.names; }

  std::optional<double> time_step() const override { return step_ ? step_ : header_.metadata_dt; }

  std::size_t rows_read() const override { return rows_read_; }

  bool next(DataBlock& block, std::size_t max_rows) override {
    const std::size_t width = request_.names.size();
    max_rows = std::max<std::size_t>(max_rows, 1);
    block.values.resize(max_rows * width);
    block.rows = 0;
    if (has_pending_) {
      std::copy(pending_.begin(), pending_.end(), block.values.begin());
      block.run = current_run_;
      block.run_starts = true;
      block.rows = 1;
      has_pending_ = false;
    }
    RowKeys keys;
    while (block.rows < max_rows) {
      double* const row = block.values.data() + block.rows * width;
      if (!read_row(row, keys)) {
        finish(rows_read_ + block.rows);
        break;
      }
      for (const auto& [to, from] : map_.copies) row[to] = row[from];
      const bool run_starts = !started_ || keys.run != current_run_;
      if (run_starts) {
        started_ = true;
        current_run_ = keys.run;
        has_previous_time_ = false;
      }
      if (map_.time >= 0) check_time(keys.t);
      if (run_starts && block.rows > 0) {
        // The row begins the next block: a block never spans two runs.
        pending_.assign(row, row + width);
        has_pending_ = true;
        break;
      }
      if (block.rows == 0) {
        block.run = current_run_;
        block.run_starts = run_starts;
      }
      ++block.rows;
    }
    block.values.resize(block.rows * width);
    rows_read_ += block.rows;
    return block.rows > 0;
  }

 protected:
  StreamReader(std::string path, const ColumnRequest& request)
      : path_(std::move(path)), request_(request) {}

  // Reads the next data row: the requested values into `row` (in request order), its time and
  // run into `keys`. False at the end of the data.
  virtual bool read_row(double* row, RowKeys& keys) = 0;
  // Where field `field` (from 0) of the row read last is.
  virtual SourceLocation field_location(int field) const = 0;
  // Where the last data row is, or the header when there is none.
  virtual SourceLocation last_row_location() const = 0;

  std::string path_;
  ColumnRequest request_;
  Header header_;
  ColumnMap map_;

 private:
  void check_time(double t) {
    if (has_previous_time_) {
      const double step = t - previous_time_;
      if (!(step > 0)) {
        fail(field_location(map_.time), "non-increasing time: t = " + shortest(t) +
                                            " after t = " + shortest(previous_time_) +
                                            " (samples must be in increasing time order)");
      }
      const double allowance = kTimeRounding * std::max(std::abs(t), std::abs(previous_time_));
      if (!step_) {
        const std::optional<double> dt = header_.metadata_dt;
        if (dt && std::abs(step - *dt) > kStepTolerance * *dt + allowance) {
          fail(field_location(map_.time), "time step " + distinguished(step, *dt).first +
                                              " of column 't' disagrees with dt=" +
                                              header_.metadata_dt_text + " in the metadata");
        }
        step_ = step;
      } else if (std::abs(step - *step_) > kStepTolerance * *step_ + allowance) {
        const auto [found, expected] = distinguished(step, *step_);
        fail(field_location(map_.time), "non-uniform time step: " + found + " after " + expected +
                                            " (t = " + shortest(t) +
                                            "; samples must be equally spaced)");
      }
    }
    previous_time_ = t;
    has_previous_time_ = true;
  }

  void finish(std::size_t rows) {
    if (rows >= request_.min_rows) return;
    fail(last_row_location(), "the data have " + plural(rows, "row") + "; at least " +
                                  std::to_string(request_.min_rows) +
                                  (request_.min_rows == 1 ? " is" : " are") + " needed");
  }

  std::optional<double> step_;
  double previous_time_ = 0;
  bool has_previous_time_ = false;
  bool started_ = false;
  long current_run_ = 0;
  std::vector<double> pending_;
  bool has_pending_ = false;
  std::size_t rows_read_ = 0;
};

// The CSV layout: one text line per row.
class CsvReader final : public StreamReader {
 public:
  CsvReader(File file, const std::string& path, const ColumnRequest& request,
            std::string_view start)
      : StreamReader(path, request), file_(std::move(file)), lines_(file_.get(), path, start) {
    header_ = read_header(path_, lines_);
    map_ = map_columns(path_, header_, request_);
    separator_ = header_.separator;
    fields_ = header_.names.size();
    field_starts_.assign(fields_, nullptr);
  }

 protected:
  bool read_row(double* row, RowKeys& keys) override {
    do {
      if (!lines_.next(line_)) return false;
    } while (is_blank_line(line_));
    ++rows_parsed_;
    if (rows_parsed_ <= request_.min_rows) {
      last_short_row_.assign(line_);
      last_short_row_line_ = lines_.line_number();
    }
    const char* p = line_.data();
    const char* const end = p + line_.size();
    std::size_t field = 0;
    if (separator_ == ' ') {
      for (;; ++field) {
        p = skip_blanks(p, end);
        if (p == end) break;
        if (field == fields_) too_many_fields(p);
        p = map_.needed[field] ? read_field(field, p, row, keys) : field_end(p, end);
      }
    } else {
      for (;; ++field) {
        if (field == fields_) too_many_fields(p);
        p = map_.needed[field] ? read_field(field, p, row, keys) : field_end(p, end);
        if (p == end) break;
        ++p;  // the separator
      }
      ++field;
    }
    if (field != fields_) {
      fail(location(line_.data()), "expected " + plural(fields_, "field") +
                                       " as in the header, found " + std::to_string(field));
    }
    return true;
  }

  SourceLocation field_location(int field) const override {
    return location(field_starts_[static_cast<std::size_t>(field)]);
  }

  SourceLocation last_row_location() const override {
    if (rows_parsed_ == 0) return text_location(path_, header_.line, 1, header_.text);
    return text_location(path_, last_short_row_line_, 1, last_short_row_);
  }

 private:
  SourceLocation location(const char* at) const {
    return text_location(path_, lines_.line_number(),
                         static_cast<std::size_t>(at - line_.data()) + 1, line_);
  }

  // The end of the field starting at `p`: the next separator or the end of the line.
  const char* field_end(const char* p, const char* end) const {
    if (separator_ == ' ') {
      while (p != end && !is_blank(*p)) ++p;
      return p;
    }
    const void* const found = std::memchr(p, separator_, static_cast<std::size_t>(end - p));
    return found == nullptr ? end : static_cast<const char*>(found);
  }

  // Reads the number in the field starting at `p` and returns the end of the field.
  const char* read_field(std::size_t field, const char* p, double* row, RowKeys& keys) {
    const char* const end = line_.data() + line_.size();
    const char* const start = skip_blanks(p, end);
    double value = 0;
    const char* after = parse_number(start, end, value);
    if (after != nullptr && separator_ != ' ') after = skip_blanks(after, end);
    if (after == nullptr || (after != end && *after != separator_ && !is_blank(*after))) {
      bad_field(field, p, "expected a number");
    }
    if (!std::isfinite(value)) bad_field(field, p, "expected a finite number");
    if (map_.output[field] >= 0) row[map_.output[field]] = value;
    if (static_cast<int>(field) == map_.time) {
      keys.t = value;
      field_starts_[field] = start;
    }
    if (static_cast<int>(field) == map_.run) {
      if (!to_run(value, keys.run)) bad_field(field, p, "expected an integer");
      field_starts_[field] = start;
    }
    return after;
  }

  // Reports the field that starts at `p`: at its first non-blank byte, if it has one.
  [[noreturn]] void bad_field(std::size_t field, const char* p, const std::string& expected) {
    const char* const end = line_.data() + line_.size();
    const char* const start = skip_blanks(p, end);
    const std::string_view text =
        trim(std::string_view(start, static_cast<std::size_t>(field_end(start, end) - start)));
    fail(location(text.empty() ? p : start),
         "column '" + header_.names[field] + "': " + expected + ", found " +
             (text.empty() ? "an empty field" : quoted_field(text)));
  }

  [[noreturn]] void too_many_fields(const char* extra) {
    const char* const end = line_.data() + line_.size();
    std::size_t count = fields_;
    if (separator_ == ' ') {
      for (const char* p = extra; (p = skip_blanks(p, end)) != end; p = field_end(p, end)) ++count;
    } else {
      count += 1 + static_cast<std::size_t>(std::count(extra, end, separator_));
    }
    fail(location(extra), "expected " + plural(fields_, "field") + " as in the header, found " +
                              std::to_string(count));
  }

  File file_;
  LineReader lines_;
  char separator_ = ',';
  std::size_t fields_ = 0;
  std::string_view line_;
  std::vector<const char*> field_starts_;  // of the `t` and `run` fields of the current row
  std::size_t rows_parsed_ = 0;
  std::string last_short_row_;  // the last row while there are fewer than min_rows
  long long last_short_row_line_ = 0;
};

// Reads up to `size` bytes, fewer only at the end of the file.
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

// Little-endian bytes to a number, whatever the byte order of this machine.
template <class Unsigned>
Unsigned load_little_endian(const unsigned char* bytes) {
  Unsigned value = 0;
  for (std::size_t i = sizeof(Unsigned); i-- > 0;) value = (value << 8) | bytes[i];
  return value;
}

double load_double(const unsigned char* bytes) {
  if constexpr (std::endian::native == std::endian::little) {
    double value;
    std::memcpy(&value, bytes, sizeof value);
    return value;
  } else {
    return std::bit_cast<double>(load_little_endian<std::uint64_t>(bytes));
  }
}

// The binary layout: a header text as in CSV, then rows of little-endian float64 values.
class BinaryReader final : public StreamReader {
 public:
  // Reads the header of `file`, whose first bytes, already read, are the magic.
  BinaryReader(File file, const std::string& path, const ColumnRequest& request)
      : StreamReader(path, request), file_(std::move(file)) {
    const SourceLocation start{path_, 1, 1, ""};
    std::array<unsigned char, 4> length_bytes;
    const std::size_t got = read_fully(file_.get(), path_, length_bytes.data(), 4);
    if (got < 4) {
      fail(start, "the file ends inside its header: expected a 4-byte header length after '" +
                      std::string(kMagic) + "', found " + plural(got, "byte"));
    }
    const std::uint32_t length = load_little_endian<std::uint32_t>(length_bytes.data());
    if (length > kMaxBinaryHeaderBytes) {
      fail(start, "the header length " + std::to_string(length) + " is too large (at most " +
                      std::to_string(kMaxBinaryHeaderBytes) + " bytes of header text)");
    }
    std::string text(length, '\0');
    const std::size_t text_got = read_fully(file_.get(), path_, text.data(), length);
    if (text_got < length) {
      fail(start, "the file ends inside its header: expected " + plural(length, "byte") +
                      " of header text, found " + std::to_string(text_got));
    }
    LineReader lines(text);
    header_ = read_header(path_, lines, /*binary=*/true);
    map_ = map_columns(path_, header_, request_);
    for (std::size_t field = 0; field < header_.names.size(); ++field) {
      if (map_.needed[field]) needed_fields_.push_back(field);
    }
    row_bytes_ = sizeof(double) * header_.names.size();
    buffer_.resize(std::max<std::size_t>(1, kChunkBytes / row_bytes_) * row_bytes_);
  }

 protected:
  bool read_row(double* row, RowKeys& keys) override {
    if (position_ == filled_) {
      if (at_end_) return false;
      filled_ = read_fully(file_.get(), path_, buffer_.data(), buffer_.size());
      position_ = 0;
      at_end_ = filled_ < buffer_.size();
      if (filled_ == 0) return false;
    }
    const std::size_t left = filled_ - position_;
    ++row_number_;
    if (left < row_bytes_) {
      fail({path_, clamp_to_int(row_number_), static_cast<int>(left / sizeof(double)) + 1, ""},
           "the file ends inside row " + std::to_string(row_number_) + ": " + plural(left, "byte") +
               " of a " + std::to_string(row_bytes_) + "-byte row");
    }
    const unsigned char* const bytes = buffer_.data() + position_;
    position_ += row_bytes_;
    for (const std::size_t field : needed_fields_) {
      const double value = load_double(bytes + sizeof(double) * field);
      if (!std::isfinite(value)) bad_value(field, value, "expected a finite number");
      if (map_.output[field] >= 0) row[map_.output[field]] = value;
      if (static_cast<int>(field) == map_.time) keys.t = value;
      if (static_cast<int>(field) == map_.run && !to_run(value, keys.run)) {
        bad_value(field, value, "expected an integer");
      }
    }
    return true;
  }

  SourceLocation field_location(int field) const override {
    return {path_, clamp_to_int(row_number_), field + 1, ""};
  }

  SourceLocation last_row_location() const override {
    if (row_number_ == 0) return text_location(path_, header_.line, 1, header_.text);
    return {path_, clamp_to_int(row_number_), 1, ""};
  }

 private:
  [[noreturn]] void bad_value(std::size_t field, double value, const std::string& expected) {
    fail(
        field_location(static_cast<int>(field)),
        "column '" + header_.names[field] + "': " + expected + ", found '" + shortest(value) + "'");
  }

  File file_;
  std::vector<std::size_t> needed_fields_;
  std::size_t row_bytes_ = 0;
  std::vector<unsigned char> buffer_;  // whole rows
  std::size_t position_ = 0, filled_ = 0;
  bool at_end_ = false;
  long long row_number_ = 0;
};

}  // namespace

std::unique_ptr<DataReader> DataReader::open(const std::string& path,
                                             const ColumnRequest& request) {
  File file(std::fopen(path.c_str(), "rb"));
  if (!file) throw Error(path + ": cannot open the data file: " + std::strerror(errno));
  // Reads are already large: stdio's buffer would only add a copy.
  std::setvbuf(file.get(), nullptr, _IONBF, 0);
  std::array<char, kMagic.size()> start;
  const std::size_t got = read_fully(file.get(), path, start.data(), start.size());
  const std::string_view first_bytes(start.data(), got);
  if (first_bytes == kMagic) return std::make_unique<BinaryReader>(std::move(file), path, request);
  return std::make_unique<CsvReader>(std::move(file), path, request, first_bytes);
}

}  // namespace momentid
