// Opens data sources: files by their content, through the format table, and columns in memory.

#include "momentid/reader.hpp"

#include <array>
#include <cerrno>
#include <cstring>

#include "data/formats.hpp"

namespace momentid {
namespace {

// Checked in order: the first format whose detector accepts the file's first bytes reads it.
constexpr std::array kFormats{
    data::DataFormat{"binary", data::is_binary, data::open_binary},
    data::DataFormat{"csv", [](std::string_view) { return true; }, data::open_csv},
};

}  // namespace

std::unique_ptr<DataReader> DataReader::open(const std::string& path,
                                             const ColumnRequest& request) {
  data::File file(std::fopen(path.c_str(), "rb"));
  if (!file) throw Error(path + ": cannot open the data file: " + std::strerror(errno));
  // Reads are already large: stdio's buffer would only add a copy.
  std::setvbuf(file.get(), nullptr, _IONBF, 0);
  std::array<char, data::kDetectBytes> start;
  const std::size_t got = data::read_fully(file.get(), path, start.data(), start.size());
  const std::string_view first_bytes(start.data(), got);
  for (const data::DataFormat& format : kFormats) {
    if (format.detect(first_bytes)) return format.open(std::move(file), path, request, first_bytes);
  }
  return nullptr;  // not reached: CSV takes every file
}

DataSource DataSource::file(std::string path) {
  DataSource source;
  source.name_ = std::move(path);
  return source;
}

DataSource DataSource::memory(MemoryData data) {
  DataSource source;
  source.name_ = data.name;
  source.memory_ = std::move(data);
  return source;
}

std::unique_ptr<DataReader> DataSource::open(const ColumnRequest& request) const {
  if (memory_) return data::open_memory(*memory_, request);
  return DataReader::open(name_, request);
}

}  // namespace momentid
