#include "data/lines.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "data/text.hpp"

namespace momentid::data {

LineReader::LineReader(std::FILE* file, std::string path, std::string_view start)
    : file_(file), path_(std::move(path)), buffer_(std::max(kChunkBytes, start.size())) {
  std::memcpy(buffer_.data(), start.data(), start.size());
  end_ = start.size();
}
LineReader::LineReader(std::string_view text) : buffer_(text.begin(), text.end()) {
  end_ = buffer_.size();
  at_end_ = true;
}

bool LineReader::next(std::string_view& line) {
  for (;;) {
    const char* const start = buffer_.data() + begin_;
    const std::size_t available = end_ - begin_;
    // (An empty buffer may have no storage: memchr must not see its null pointer.)
    const void* const newline = available == 0 ? nullptr : std::memchr(start, '\n', available);
    if (newline != nullptr) {
      const std::size_t length = static_cast<const char*>(newline) - start;
      line_offset_ = base_ + begin_;
      begin_ += length + 1;
      line = deliver(start, length);
      return true;
    }
    if (at_end_) {
      if (available == 0) return false;
      line_offset_ = base_ + begin_;
      begin_ = end_;
      line = deliver(start, available);
      return true;
    }
    refill();
  }
}

std::string_view LineReader::deliver(const char* start, std::size_t length) {
  ++line_number_;
  if (length > 0 && start[length - 1] == '\r') --length;
  return {start, length};
}

void LineReader::seek(std::uint64_t offset) {
  if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) {
    throw Error(path_ + ": cannot read the data file: " + std::strerror(errno));
  }
  base_ = offset;
  begin_ = end_ = 0;
  at_end_ = false;
  line_number_ = 0;
}

void LineReader::refill() {
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
  base_ += begin_;
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

}  // namespace momentid::data
