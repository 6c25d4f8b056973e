#pragma once
// Values as little-endian bytes, for states that travel between processes or files.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "momentid/error.hpp"

namespace momentid {

// Writes integers and IEEE-754 doubles little-endian, whatever the byte order of this machine.
class ByteWriter {
 public:
  void bytes(const char* data, std::size_t count) { out_.insert(out_.end(), data, data + count); }
  void u8(std::uint8_t value) { out_.push_back(value); }
  void u32(std::uint32_t value) { little_endian(value, 4); }
  void u64(std::uint64_t value) { little_endian(value, 8); }
  void i32(std::int32_t value) { u32(static_cast<std::uint32_t>(value)); }
  void f64(double value) { u64(std::bit_cast<std::uint64_t>(value)); }
  std::vector<std::uint8_t> take() { return std::move(out_); }

 private:
  void little_endian(std::uint64_t value, int count) {
    for (int b = 0; b < count; ++b) out_.push_back(static_cast<std::uint8_t>(value >> (8 * b)));
  }
  std::vector<std::uint8_t> out_;
};

// Reads what a ByteWriter wrote, naming the field being read when the bytes end too soon;
// `name` says whose bytes they are in messages ("moment accumulator bytes").
class ByteReader {
 public:
  ByteReader(std::span<const std::uint8_t> bytes, std::string name)
      : bytes_(bytes), name_(std::move(name)) {}

  std::span<const std::uint8_t> take(std::size_t count, const std::string& what) {
    need(count, what);
    const auto out = bytes_.subspan(at_, count);
    at_ += count;
    return out;
  }
  std::uint8_t u8(const std::string& what) { return take(1, what)[0]; }
  std::uint32_t u32(const std::string& what) {
    return static_cast<std::uint32_t>(little_endian(4, what));
  }
  std::uint64_t u64(const std::string& what) { return little_endian(8, what); }
  std::int32_t i32(const std::string& what) { return static_cast<std::int32_t>(u32(what)); }
  double f64(const std::string& what) { return std::bit_cast<double>(u64(what)); }
  // A count of entries of at least `bytes_each` bytes, checked against the bytes left.
  std::size_t count(std::size_t bytes_each, const std::string& what) {
    const std::uint64_t n = u64("the number of " + what);
    if (n > (bytes_.size() - at_) / bytes_each) {
      throw Error("truncated " + name_ + ": " + std::to_string(bytes_.size()) + " bytes, but " +
                  std::to_string(n) + " " + what + " need at least " + std::to_string(bytes_each) +
                  " bytes each from byte " + std::to_string(at_));
    }
    return static_cast<std::size_t>(n);
  }
  std::size_t position() const { return at_; }

 private:
  void need(std::size_t count, const std::string& what) const {
    if (bytes_.size() - at_ < count) {
      throw Error("truncated " + name_ + ": " + std::to_string(bytes_.size()) + " bytes, but " +
                  what + " needs " + std::to_string(count) + " bytes from byte " +
                  std::to_string(at_));
    }
  }
  std::uint64_t little_endian(std::size_t count, const std::string& what) {
    std::uint64_t value = 0;
    const auto b = take(count, what);
    for (std::size_t i = 0; i < count; ++i) value |= std::uint64_t{b[i]} << (8 * i);
    return value;
  }
  std::span<const std::uint8_t> bytes_;
  std::string name_;
  std::size_t at_ = 0;
};

}  // namespace momentid
