// Binary layout (docs/data-files.md, "Binary"): errors in the header text are located by the line
// and byte column of that text, errors in the rows by the row number (from 1) and the column
// number (from 1).

#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <utility>
#include <vector>

#include "common/decimal.hpp"
#include "data/format.hpp"
#include "data/formats.hpp"
#include "data/lines.hpp"
#include "data/stream_reader.hpp"
#include "data/text.hpp"
#include "moments/kernel.hpp"

namespace momentid::data {
namespace {

constexpr std::uint32_t kMaxBinaryHeaderBytes = std::uint32_t{16} << 20;
constexpr std::size_t kChunkBytes = std::size_t{1} << 20;

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

// Whether each of the `count` doubles (native byte order) from `bytes` is finite: its exponent
// bits not all set.
MOMENTID_KERNEL bool all_finite(const unsigned char* bytes, std::size_t count) {
  constexpr std::uint64_t kExponent = 0x7ff0000000000000;
  std::uint64_t infinite = 0;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint64_t bits;
    std::memcpy(&bits, bytes + sizeof bits * i, sizeof bits);
    infinite |= static_cast<std::uint64_t>((bits & kExponent) == kExponent);
  }
  return infinite == 0;
}

// The binary layout: a header text as in CSV, then rows of little-endian float64 values.
class BinaryReader final : public StreamReader {
 public:
  // Reads the header of `file`, whose first bytes, already read, are the magic.
  BinaryReader(File file, const std::string& path, const ColumnRequest& request)
      : StreamReader(path, request), file_(std::move(file)) {
    takes_many_rows_ = true;
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
      if (!map_.needed[field]) continue;
      needed_fields_.push_back(field);
      takes_.push_back({field, map_.output[field], static_cast<int>(field) == map_.time});
      const std::size_t offset = sizeof(double) * field;
      if (map_.output[field] >= 0) {
        outputs_.emplace_back(offset, static_cast<std::size_t>(map_.output[field]));
      }
      if (static_cast<int>(field) == map_.time) time_offset_ = offset;
    }
    row_bytes_ = sizeof(double) * header_.names.size();
    data_start_ = kMagic.size() + 4 + length;
    buffer_.resize(std::max<std::size_t>(1, kChunkBytes / row_bytes_) * row_bytes_);
  }

 protected:
  bool read_row(double* row, RowKeys& keys) override {
    if (position_ == filled_ && !refill()) return false;
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
      take_value(field, value, row, keys,
                 [&](const std::string& expected) { bad_value(field, value, expected); });
    }
    return true;
  }

  // The rows the buffer holds whole, up to the first with a value that is not finite. Where every
  // value of the rows is finite, the columns not read included (the common case, tested at once),
  // each is copied where it goes without a test of its own; otherwise the rows are taken one by
  // one, to stop before the first row with a requested value that is not finite.
  std::size_t read_rows(double* rows, double* times, std::size_t count) override {
    if (position_ == filled_ && !refill()) return 0;
    const std::size_t width = request_.names.size();
    std::size_t n = std::min(count, (filled_ - position_) / row_bytes_);
    const unsigned char* const first = buffer_.data() + position_;
    if (std::endian::native == std::endian::little && all_finite(first, n * header_.names.size())) {
      for (std::size_t r = 0; r < n; ++r) {
        const unsigned char* const bytes = first + r * row_bytes_;
        double* const row = rows + r * width;
        for (const auto& [offset, output] : outputs_) row[output] = load_double(bytes + offset);
        if (time_offset_) times[r] = load_double(bytes + *time_offset_);
      }
      position_ += n * row_bytes_;
      row_number_ += static_cast<long long>(n);
      return n;
    }
    for (std::size_t r = 0; r < n; ++r) {
      const unsigned char* const bytes = buffer_.data() + position_ + r * row_bytes_;
      double* const row = rows + r * width;
      bool finite = true;
      for (const Take& take : takes_) {
        const double value = load_double(bytes + sizeof(double) * take.field);
        finite = finite && std::isfinite(value);
        if (take.output >= 0) row[take.output] = value;
        if (take.time) times[r] = value;
      }
      if (!finite) {
        n = r;
        break;
      }
    }
    position_ += n * row_bytes_;
    row_number_ += static_cast<long long>(n);
    return n;
  }

  void unread_rows(std::size_t count) override {
    position_ -= count * row_bytes_;
    row_number_ -= static_cast<long long>(count);
  }

  std::optional<double> fraction_read() const override { return file_fraction(file_.get()); }

  Bounds seek_part(const ColumnRequest::Part& part) override {
    const std::uint64_t size = file_size(file_.get()).value_or(data_start_);
    std::uint64_t first = 0;
    // A row cut short at the end belongs to the last part, which reports it.
    const Bounds bounds =
        row_bounds(size > data_start_ ? (size - data_start_) / row_bytes_ : 0, part, first);
    if (fseeko(file_.get(), static_cast<off_t>(data_start_ + first * row_bytes_), SEEK_SET) != 0) {
      throw Error(path_ + ": cannot read the data file: " + std::strerror(errno));
    }
    row_number_ = static_cast<long long>(first);
    return bounds;
  }

  std::uint64_t row_position() const override {
    return static_cast<std::uint64_t>(row_number_ - 1);
  }

  SourceLocation field_location(int field) const override {
    return {path_, clamp_to_int(row_number_), field + 1, ""};
  }

  SourceLocation last_row_location() const override {
    if (row_number_ == 0) return text_location(path_, header_.line, 1, header_.text);
    return {path_, clamp_to_int(row_number_), 1, ""};
  }

 private:
  // Fills the buffer with the next whole rows; false at the end of the file.
  bool refill() {
    if (at_end_) return false;
    filled_ = read_fully(file_.get(), path_, buffer_.data(), buffer_.size());
    position_ = 0;
    at_end_ = filled_ < buffer_.size();
    return filled_ > 0;
  }

  [[noreturn]] void bad_value(std::size_t field, double value, const std::string& expected) {
    fail(field_location(static_cast<int>(field)), "column '" + header_.names[field] +
                                                      "': " + expected + ", found '" +
                                                      shortest_decimal(value) + "'");
  }

  File file_;
  std::vector<std::size_t> needed_fields_;
  // Per needed field: where read_rows() puts it.
  struct Take {
    std::size_t field;
    int output;  // ColumnMap::output
    bool time;
  };
  std::vector<Take> takes_;
  // The same, as read_rows copies them: each field that goes to a row, its byte offset in the row
  // and its place, and the time's offset.
  std::vector<std::pair<std::size_t, std::size_t>> outputs_;
  std::optional<std::size_t> time_offset_;
  std::size_t row_bytes_ = 0;
  std::uint64_t data_start_ = 0;       // the offset of the first row
  std::vector<unsigned char> buffer_;  // whole rows
  std::size_t position_ = 0, filled_ = 0;
  bool at_end_ = false;
  long long row_number_ = 0;
};

}  // namespace

bool is_binary(std::string_view first_bytes) { return first_bytes.starts_with(kMagic); }

std::unique_ptr<DataReader> open_binary(File file, const std::string& path,
                                        const ColumnRequest& request, std::string_view) {
  return std::make_unique<BinaryReader>(std::move(file), path, request);
}

}  // namespace momentid::data
