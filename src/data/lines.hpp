#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace momentid::data {

// Delivers the lines of a file, or of a text in memory, one at a time, without their line
// break (LF or CR LF). A file is read in chunks of kChunkBytes; a line is a view into the
// current chunk, valid until the next call.
class LineReader {
 public:
  static constexpr std::size_t kChunkBytes = std::size_t{1} << 20;
  // A longer "line" means the file is not a text data file; stop before memory runs out.
  static constexpr std::size_t kMaxLineBytes = std::size_t{256} << 20;

  // Reads `file`, whose first bytes, already read, are `start`.
  LineReader(std::FILE* file, std::string path, std::string_view start);
  // Reads the lines of `text`.
  explicit LineReader(std::string_view text);

  bool next(std::string_view& line);

  // The line the last call of next() delivered, from 1 (from where seek() put the reader).
  long long line_number() const { return line_number_; }
  // The byte offset in the file of that line, and of the next line.
  std::uint64_t line_offset() const { return line_offset_; }
  std::uint64_t next_offset() const { return base_ + begin_; }
  // Reads on from byte `offset` of the file, which starts a line; lines are numbered from there.
  void seek(std::uint64_t offset);

 private:
  std::string_view deliver(const char* start, std::size_t length);
  // Keeps the unfinished line, at the front of the buffer, and appends the next chunk.
  void refill();

  std::FILE* file_ = nullptr;
  std::string path_;
  std::vector<char> buffer_;
  std::size_t begin_ = 0, end_ = 0;
  bool at_end_ = false;
  long long line_number_ = 0;
  std::uint64_t base_ = 0;  // the file offset of buffer_[0]
  std::uint64_t line_offset_ = 0;
};

}  // namespace momentid::data
