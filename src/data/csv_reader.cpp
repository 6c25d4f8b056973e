// The CSV layout (docs/data-files.md, "CSV").
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

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "data/formats.hpp"
#include "data/lines.hpp"
#include "data/stream_reader.hpp"
#include "data/text.hpp"

namespace momentid::data {
namespace {

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
    if (request_.layout.decimal == ',' && separator_ == ',') {
      fail(text_location(path_, header_.line, 1, header_.text),
           "a decimal comma needs fields separated by ';' or blanks, but the header separates "
           "them by ','");
    }
    for (std::size_t k = 0; k < request_.layout.skip_rows; ++k) {
      if (!lines_.next(line_)) break;
    }
    data_start_ = lines_.next_offset();
    skip_units_row();
  }

 protected:
  bool read_row(double* row, RowKeys& keys) override {
    if (peeked_) {
      peeked_ = false;
    } else {
      do {
        if (!lines_.next(line_)) return false;
      } while (is_blank_line(line_));
    }
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

  std::optional<double> fraction_read() const override { return file_fraction(file_.get()); }

  SourceLocation field_location(int field) const override {
    return location(field_starts_[static_cast<std::size_t>(field)]);
  }

  // A part is a range of bytes: its rows are the lines that start in it.
  Bounds seek_part(const ColumnRequest::Part& part) override {
    const std::uint64_t size = file_size(file_.get()).value_or(data_start_);
    const std::uint64_t data = size > data_start_ ? size - data_start_ : 0;
    std::uint64_t ignored = 0;
    Bounds bounds = row_bounds(data, part, ignored);
    bounds.begin += data_start_;
    if (part.index + 1 < part.count) bounds.end += data_start_;
    // The context: `before` rows (not blank lines) before the first line that starts in the part.
    std::uint64_t start = first_line_at(bounds.begin);
    for (std::size_t k = 0; k < part.before && start > data_start_; ++k) {
      start = previous_row(start);
    }
    lines_.seek(start);
    peeked_ = false;
    seek_start_ = start;
    // The units-row hint is for the file's first row.
    if (start > data_start_) rows_parsed_ = 1;
    return bounds;
  }

  std::uint64_t row_position() const override { return lines_.line_offset(); }

  long long lines_skipped() const override {
    if (seek_start_ == 0) return 0;
    if (!lines_before_) lines_before_ = count_lines(seek_start_);
    return *lines_before_;
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

  // Whether a field of the current line reads as a number; `text`: whether one is neither a
  // number nor empty nor a missing value.
  bool holds_a_number(bool* text = nullptr) const {
    const char* const end = line_.data() + line_.size();
    for (const char* p = line_.data();; ++p) {
      const char* const start = skip_blanks(p, end);
      const char* const stop = field_end(start, end);
      double value = 0;
      const char* after = parse_number(start, end, value, request_.layout.decimal);
      if (after != nullptr && skip_blanks(after, end) >= stop) return true;
      if (text != nullptr && !is_missing_value(trim(std::string_view(
                                 start, static_cast<std::size_t>(stop - start))))) {
        *text = true;
      }
      p = stop;
      if (p == end) return false;
    }
  }

  // The units row a DAQ writes under the header (`s,m/s^2,N`): a first row with text in a
  // field and no number in any is not data, and is skipped as --skip-rows 1 skips it. Any other
  // first row is kept for read_row.
  void skip_units_row() {
    do {
      if (!lines_.next(line_)) return;
    } while (is_blank_line(line_));
    bool text = false;
    if (!holds_a_number(&text) && text) {
      data_start_ = lines_.next_offset();
    } else {
      peeked_ = true;
    }
  }

  // An empty field, or a missing-value marker as spreadsheets and pandas write them.
  static bool is_missing_value(std::string_view text) {
    const auto is = [&](std::string_view marker) {
      return std::equal(text.begin(), text.end(), marker.begin(), marker.end(),
                        [](char a, char b) { return (a | 0x20) == (b | 0x20); });
    };
    return text.empty() || is("nan") || is("na") || is("n/a");
  }

  // Reads the number in the field starting at `p` and returns the end of the field.
  const char* read_field(std::size_t field, const char* p, double* row, RowKeys& keys) {
    const char* const end = line_.data() + line_.size();
    const char* const start = skip_blanks(p, end);
    // A field that starts like a number (a digit, a sign, a point) is not a missing value (empty,
    // nan, na or n/a), and its end is where the number ends.
    const bool numeric = start != end && ((*start >= '0' && *start <= '9') || *start == '-' ||
                                          *start == '+' || *start == '.');
    if (!numeric) {
      const char* const stop = field_end(start, end);
      if (is_missing_value(trim(std::string_view(start, static_cast<std::size_t>(stop - start))))) {
        if (!pass_over_missing(keys, field))
          bad_field(field, p, "expected a number (" + missing_value_hint() + ")");
        field_starts_[field] = start;
        return stop;
      }
    }
    double value = 0;
    const char* after = parse_number(start, end, value, request_.layout.decimal);
    if (after != nullptr && separator_ != ' ') after = skip_blanks(after, end);
    if (after == nullptr || (after != end && *after != separator_ && !is_blank(*after))) {
      // "1,5" in a ';'-separated file: a decimal comma.
      const char* const stop = field_end(start, end);
      const bool comma = request_.layout.decimal == '.' && separator_ != ',' &&
                         std::memchr(start, ',', static_cast<std::size_t>(stop - start)) != nullptr;
      // A first row none of whose fields is a number: units or descriptions (`s`, `m/s^2`).
      const bool units = rows_parsed_ == 1 && !holds_a_number();
      bad_field(field, p,
                comma ? "expected a number (with a decimal comma? give " +
                            UsageError::mention("decimal") + " ,)"
                : units ? "expected a number (a units row? give " +
                              UsageError::mention("skip_rows") + " 1)"
                        : std::string("expected a number"));
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

  // Reads bytes [offset, offset + size) of the file (fewer at its end).
  std::size_t read_at(std::uint64_t offset, char* into, std::size_t size) const {
    std::size_t got = 0;
    while (got < size) {
      const ssize_t n =
          pread(fileno(file_.get()), into + got, size - got, static_cast<off_t>(offset + got));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw Error(path_ + ": cannot read the data file: " + std::strerror(errno));
      if (n == 0) break;
      got += static_cast<std::size_t>(n);
    }
    return got;
  }

  // The offset of the first line that starts at or after `offset` (past the data's start).
  std::uint64_t first_line_at(std::uint64_t offset) const {
    if (offset <= data_start_) return data_start_;
    std::vector<char> buffer(1 << 16);
    for (std::uint64_t at = offset - 1;;) {
      const std::size_t got = read_at(at, buffer.data(), buffer.size());
      if (got == 0) return at;
      const void* newline = std::memchr(buffer.data(), '\n', got);
      if (newline != nullptr) return at + (static_cast<const char*>(newline) - buffer.data()) + 1;
      at += got;
    }
  }

  // The start of the last row (a line that is not blank) that begins before `offset`, a line
  // start past the data's start; the data's start when there is none.
  std::uint64_t previous_row(std::uint64_t offset) const {
    std::vector<char> buffer;
    for (std::size_t window = 1 << 12;; window *= 2) {
      const std::uint64_t low = offset - std::min<std::uint64_t>(window, offset - data_start_);
      buffer.resize(static_cast<std::size_t>(offset - low));
      buffer.resize(read_at(low, buffer.data(), buffer.size()));
      // Lines end at the newlines; the one just before `offset` is buffer's last byte.
      std::size_t end = buffer.size();
      while (end > 0) {
        std::size_t begin = end - 1;
        while (begin > 0 && buffer[begin - 1] != '\n') --begin;
        if (begin == 0 && low > data_start_) break;  // the line may start before the window
        std::string_view line(buffer.data() + begin, end - 1 - begin);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (!is_blank_line(line)) return low + begin;
        end = begin;
      }
      if (low == data_start_ && end == 0) return data_start_;
    }
  }

  // Newlines before byte `offset`: the lines that precede it.
  long long count_lines(std::uint64_t offset) const {
    std::vector<char> buffer(1 << 20);
    long long lines = 0;
    for (std::uint64_t at = 0; at < offset;) {
      const std::size_t got =
          read_at(at, buffer.data(),
                  static_cast<std::size_t>(std::min<std::uint64_t>(buffer.size(), offset - at)));
      if (got == 0) break;
      lines += std::count(buffer.data(), buffer.data() + got, '\n');
      at += got;
    }
    return lines;
  }

  File file_;
  LineReader lines_;
  std::uint64_t data_start_ = 0;  // the offset of the first line after the header
  std::uint64_t seek_start_ = 0;  // where seek_part() put the reader
  mutable std::optional<long long> lines_before_;
  char separator_ = ',';
  std::size_t fields_ = 0;
  std::string_view line_;
  // Of the `t` and `run` fields of the current row, and of a missing value.
  std::vector<const char*> field_starts_;
  std::size_t rows_parsed_ = 0;
  bool peeked_ = false;         // line_ holds the first row, read by skip_units_row()
  std::string last_short_row_;  // the last row while there are fewer than min_rows
  long long last_short_row_line_ = 0;
};

}  // namespace

std::unique_ptr<DataReader> open_csv(File file, const std::string& path,
                                     const ColumnRequest& request, std::string_view start) {
  return std::make_unique<CsvReader>(std::move(file), path, request, start);
}

}  // namespace momentid::data
