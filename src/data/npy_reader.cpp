// NumPy .npy files (format versions 1 to 3): a header holding a Python dict literal with the
// keys 'descr', 'fortran_order' and 'shape', then the array's bytes, read as they are needed
// (not mapped: a file cut short while it is read must be an error, not SIGBUS).
// A 1-D array is one channel named after the file (`disp.npy` is `disp`); an N x K array is K
// channels, named by FileLayout::column_names (`--names`) or `NAME[:, k]`. Channels in
// other .npy files join through ColumnRequest::rename (`--columns x=force.npy`): each such file
// holds one 1-D array, the channel named as written there.

#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>

#include "data/column_store.hpp"
#include "data/formats.hpp"

namespace momentid::data {
namespace {

constexpr std::string_view kNpyMagic = "\x93NUMPY";

// One array, read from its file.
class NpyArray {
 public:
  NpyArray(const std::string& path, File file) : path_(path), file_(std::move(file)) {
    struct stat info;
    if (fstat(fileno(file_.get()), &info) != 0 || !S_ISREG(info.st_mode)) {
      fail(where(), "cannot read the file as a NumPy array: not a regular file");
    }
    size_ = static_cast<std::size_t>(info.st_size);
    if (size_ < 10) fail(where(), "the file ends inside its NumPy header");
    parse_header();
  }

  std::size_t rows() const { return shape_[0]; }
  std::size_t columns() const { return shape_.size() == 2 ? shape_[1] : 1; }
  bool two_dimensional() const { return shape_.size() == 2; }

  // Values [first, first + count) of column `column`. The rows of a C-order array with several
  // columns are read once for all of them.
  void read(std::size_t column, std::size_t first, std::size_t count, double* out) {
    const bool contiguous = fortran_ || columns() == 1;
    const std::size_t step = contiguous ? 1 : columns();
    if (contiguous) {
      read_bytes((column * rows() + first) * width_, count * width_);
    } else if (first != cached_first_ || count != cached_count_) {
      read_bytes(first * columns() * width_, count * columns() * width_);
      cached_first_ = first;
      cached_count_ = count;
    }
    const unsigned char* at = buffer_.data() + (contiguous ? 0 : column * width_);
    if (width_ == 8 && little_ == (std::endian::native == std::endian::little)) {
      for (std::size_t i = 0; i < count; ++i, at += step * 8) std::memcpy(out + i, at, 8);
      return;
    }
    for (std::size_t i = 0; i < count; ++i, at += step * width_) out[i] = value(at);
  }

 private:
  SourceLocation where() const { return {path_, 1, 1, ""}; }

  // `size` bytes at `offset` of the array's data into buffer_; the file must hold them.
  void read_bytes(std::size_t offset, std::size_t size) {
    buffer_.resize(size);
    if (read_at(data_offset_ + offset, buffer_.data(), size) < size) {
      fail(where(), "the file ends inside the array: it was cut short while it was read");
    }
  }

  // Up to `size` bytes at `offset` of the file (fewer at its end).
  std::size_t read_at(std::size_t offset, unsigned char* into, std::size_t size) const {
    std::size_t got = 0;
    while (got < size) {
      const ssize_t n =
          pread(fileno(file_.get()), into + got, size - got, static_cast<off_t>(offset + got));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) fail(where(), std::string("cannot read the file: ") + std::strerror(errno));
      if (n == 0) break;
      got += static_cast<std::size_t>(n);
    }
    return got;
  }

  double value(const unsigned char* at) const {
    std::uint64_t bits = 0;
    for (std::size_t b = 0; b < width_; ++b) {
      const std::size_t shift = little_ ? 8 * b : 8 * (width_ - 1 - b);
      bits |= std::uint64_t{at[b]} << shift;
    }
    if (width_ == 8) return std::bit_cast<double>(bits);
    return static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(bits)));
  }

  // The text of key `key` in the header dict, up to the next top-level ',' or '}'.
  std::string_view entry(std::string_view header, std::string_view key) const {
    // The key as Python writes it, in single quotes (or double quotes, as JSON would).
    std::size_t at = std::string_view::npos;
    for (char quote : {'\'', '"'}) {
      std::string quoted(1, quote);
      quoted.append(key);
      quoted.push_back(quote);
      at = std::min(at, header.find(quoted));
    }
    if (at == std::string_view::npos) {
      fail(where(), "the NumPy header has no '" + std::string(key) + "'");
    }
    const std::size_t colon = header.find(':', at);
    if (colon == std::string_view::npos) {
      fail(where(), "the NumPy header has no value for '" + std::string(key) + "'");
    }
    std::size_t end = colon + 1;
    int depth = 0;
    for (; end < header.size(); ++end) {
      const char c = header[end];
      if (c == '(' || c == '[') ++depth;
      if (c == ')' || c == ']') --depth;
      if (depth == 0 && (c == ',' || c == '}')) break;
      if (depth < 0) break;
    }
    return trim(header.substr(colon + 1, end - colon - 1));
  }

  void parse_header() {
    unsigned char lead[12] = {};
    read_at(0, lead, std::min<std::size_t>(size_, sizeof lead));
    const unsigned major = lead[6];
    std::size_t length = 0, start = 0;
    if (major == 1) {
      length = lead[8] | (std::size_t{lead[9]} << 8);
      start = 10;
    } else if (major == 2 || major == 3) {
      if (size_ < 12) fail(where(), "the file ends inside its NumPy header");
      length = lead[8] | (std::size_t{lead[9]} << 8) | (std::size_t{lead[10]} << 16) |
               (std::size_t{lead[11]} << 24);
      start = 12;
    } else {
      fail(where(), "NumPy format version " + std::to_string(major) + " (expected 1, 2 or 3)");
    }
    if (start + length > size_) fail(where(), "the file ends inside its NumPy header");
    std::vector<unsigned char> text(length);
    if (read_at(start, text.data(), length) < length) {
      fail(where(), "the file ends inside its NumPy header");
    }
    const std::string_view header(reinterpret_cast<const char*>(text.data()), length);
    std::string descr(entry(header, "descr"));
    if (descr.size() >= 2 && (descr.front() == '\'' || descr.front() == '"')) {
      descr = descr.substr(1, descr.size() - 2);
    }
    if (descr == "<f8" || descr == ">f8" || descr == "<f4" || descr == ">f4") {
      little_ = descr[0] == '<';
      width_ = descr[2] == '8' ? 8 : 4;
    } else {
      fail(where(), "the array holds '" + descr +
                        "' values: expected float64 or float32 ('<f8', '>f8', '<f4', '>f4')");
    }
    const std::string_view order = entry(header, "fortran_order");
    fortran_ = order == "True";
    std::string_view shape = entry(header, "shape");
    if (shape.size() < 2 || shape.front() != '(' || shape.back() != ')') {
      fail(where(), "the NumPy header's shape is not a tuple: " + std::string(shape));
    }
    shape.remove_prefix(1);
    shape.remove_suffix(1);
    while (!trim(shape).empty()) {
      const std::size_t comma = std::min(shape.find(','), shape.size());
      const std::string_view item = trim(shape.substr(0, comma));
      if (!item.empty()) {
        double n = 0;
        if (!is_number(item, n) || n < 0 || n != std::floor(n)) {
          fail(where(), "the NumPy header's shape has '" + std::string(item) + "'");
        }
        shape_.push_back(static_cast<std::size_t>(n));
      }
      shape.remove_prefix(std::min(comma + 1, shape.size()));
    }
    if (shape_.empty() || shape_.size() > 2) {
      fail(where(), "the array has " + std::to_string(shape_.size()) +
                        " dimensions: expected 1 (a channel) or 2 (samples x channels)");
    }
    data_offset_ = start + length;
    // The array's bytes, which must all be in the file (a shape too large wraps around).
    std::size_t bytes = width_;
    bool overflow = false;
    for (std::size_t n : shape_) overflow = overflow || __builtin_mul_overflow(bytes, n, &bytes);
    if (overflow || bytes > size_ - start - length) {
      fail({path_,
            clamp_to_int(static_cast<long long>((size_ - start - length) / width_ / columns()) + 1),
            1, ""},
           "the file ends inside the array: " + plural(size_ - start - length, "byte") +
               " of data for an array of shape " + shape_text() + " of " + std::to_string(width_) +
               "-byte values");
    }
  }

  // As numpy prints a shape: (5,) or (5, 4).
  std::string shape_text() const {
    std::string out(1, '(');
    out.append(std::to_string(shape_[0]));
    for (std::size_t k = 1; k < shape_.size(); ++k) {
      out.append(", ");
      out.append(std::to_string(shape_[k]));
    }
    out.append(shape_.size() == 1 ? ",)" : ")");
    return out;
  }

  std::string path_;
  File file_;
  std::size_t size_ = 0;
  std::size_t data_offset_ = 0;  // where the array's values begin
  // The bytes last read, and for a C-order array of several columns (which always reads whole
  // rows) the rows they are.
  std::vector<unsigned char> buffer_;
  std::size_t cached_first_ = 0, cached_count_ = 0;
  std::vector<std::size_t> shape_;
  std::size_t width_ = 8;
  bool little_ = true, fortran_ = false;
};

class NpyStore final : public ColumnStore {
 public:
  NpyStore(File file, const std::string& path, const ColumnRequest& request) {
    arrays_.push_back(std::make_unique<NpyArray>(path, std::move(file)));
    const NpyArray& main = *arrays_.front();
    const std::string stem = std::filesystem::path(path).stem().string();
    if (!request.layout.column_names.empty() &&
        request.layout.column_names.size() != main.columns()) {
      fail({path, 1, 1, ""}, UsageError::mention("column_names") + " gives " +
                                 plural(request.layout.column_names.size(), "name") + " for " +
                                 plural(main.columns(), "column"));
    }
    for (std::size_t k = 0; k < main.columns(); ++k) {
      names_.push_back(!request.layout.column_names.empty() ? request.layout.column_names[k]
                       : main.two_dimensional() ? stem + "[:, " + std::to_string(k) + "]"
                                                : stem);
      channels_.emplace_back(0, k);
    }
    for (const auto& [variable, column] : request.rename) {
      if (!column.ends_with(".npy") ||
          std::find(names_.begin(), names_.end(), column) != names_.end()) {
        continue;
      }
      File other(std::fopen(column.c_str(), "rb"));
      if (!other) fail({column, 1, 1, ""}, std::string("cannot open: ") + std::strerror(errno));
      arrays_.push_back(std::make_unique<NpyArray>(column, std::move(other)));
      if (arrays_.back()->two_dimensional()) {
        fail({column, 1, 1, ""}, "a channel in a file of its own must be a 1-D array, found " +
                                     std::to_string(arrays_.back()->columns()) + " columns");
      }
      names_.push_back(column);
      channels_.emplace_back(arrays_.size() - 1, 0);
    }
  }

  const char* kind() const override { return "column"; }
  std::vector<std::string> names() const override { return names_; }
  void prepare(std::size_t) override {}
  std::size_t length(std::size_t channel) const override {
    return arrays_[channels_[channel].first]->rows();
  }
  void read(std::size_t channel, std::size_t first, std::size_t count, double* out) override {
    const auto [array, column] = channels_[channel];
    arrays_[array]->read(column, first, count, out);
  }

 private:
  std::vector<std::unique_ptr<NpyArray>> arrays_;
  std::vector<std::string> names_;
  std::vector<std::pair<std::size_t, std::size_t>> channels_;  // (array, column)
};

}  // namespace

bool is_npy(std::string_view first_bytes) { return first_bytes.starts_with(kNpyMagic); }

std::unique_ptr<DataReader> open_npy(File file, const std::string& path,
                                     const ColumnRequest& request, std::string_view) {
  return open_column_store(std::make_unique<NpyStore>(std::move(file), path, request), path,
                           request);
}

}  // namespace momentid::data
