// Opens data sources: files by their content, through the format table, and columns in memory.

#include "momentid/reader.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <optional>
#include <vector>

#include "data/formats.hpp"
#include "data/temporary.hpp"

namespace momentid::data {

bool is_mat(std::string_view first_bytes) {
  // The 116-byte text header of levels 5 and 7.3 begins with these words.
  return first_bytes.starts_with("MATLAB 5") || first_bytes.starts_with("MATLAB 7");
}

bool is_hdf5(std::string_view first_bytes) { return first_bytes.starts_with("\x89HDF\r\n\x1a\n"); }

// A format this build was made without is recognised, and said to be missing.
#ifndef MOMENTID_WITH_MATIO
std::unique_ptr<DataReader> open_mat(File, const std::string& path, const ColumnRequest&,
                                     std::string_view) {
  fail({path, 1, 1, ""}, "this is a MATLAB file, and this momentid was built without matio");
}
#endif
#ifndef MOMENTID_WITH_HDF5
std::unique_ptr<DataReader> open_hdf5(File, const std::string& path, const ColumnRequest&,
                                      std::string_view) {
  fail({path, 1, 1, ""}, "this is an HDF5 file, and this momentid was built without HDF5");
}
#endif

}  // namespace momentid::data

namespace momentid {
namespace {

// Checked in order: the first format whose detector accepts the file's first bytes reads it.
constexpr std::array kFormats{
    data::DataFormat{"binary", data::is_binary, data::open_binary},
    data::DataFormat{"npy", data::is_npy, data::open_npy},
    data::DataFormat{"mat", data::is_mat, data::open_mat},
    data::DataFormat{"hdf5", data::is_hdf5, data::open_hdf5},
    data::DataFormat{"csv", [](std::string_view) { return true; }, data::open_csv},
};

}  // namespace

std::unique_ptr<DataReader> DataReader::open(const std::string& path, const ColumnRequest& request,
                                             const std::string& name) {
  const std::string& shown = name.empty() ? path : name;
  data::File file(std::fopen(path.c_str(), "rb"));
  if (!file) throw Error(shown + ": cannot open the data file: " + std::strerror(errno));
  // Reads are already large: stdio's buffer would only add a copy.
  std::setvbuf(file.get(), nullptr, _IONBF, 0);
  std::array<char, data::kDetectBytes> start;
  const std::size_t got = data::read_fully(file.get(), shown, start.data(), start.size());
  const std::string_view first_bytes(start.data(), got);
  for (const data::DataFormat& format : kFormats) {
    if (format.detect(first_bytes)) {
      return format.open(std::move(file), shown, request, first_bytes);
    }
  }
  return nullptr;  // not reached: CSV takes every file
}

void MissingSummary::add(const MissingSummary& later) {
  if (!first && later.first) first = later.first;
  rows += later.rows;
  splits += later.splits;
  joins += later.joins;
}

// What tells a file that changed from the one first read: its size, modification time and inode
// (outside the anonymous namespace: DataSource::Stamps holds it).
struct FileStamp {
  off_t size = 0;
  timespec modified{};
  ino_t inode = 0;
  bool operator==(const FileStamp& o) const {
    return size == o.size && modified.tv_sec == o.modified.tv_sec &&
           modified.tv_nsec == o.modified.tv_nsec && inode == o.inode;
  }
};

namespace {

// The stamps of `paths`; a file that cannot be examined has none (its reader says why).
std::vector<std::optional<FileStamp>> stamps_of(const std::vector<std::string>& paths) {
  std::vector<std::optional<FileStamp>> out;
  for (const std::string& path : paths) {
    struct stat s {};
    out.push_back(::stat(path.c_str(), &s) == 0
                      ? std::optional<FileStamp>({s.st_size, s.st_mtim, s.st_ino})
                      : std::nullopt);
  }
  return out;
}

}  // namespace

struct DataSource::Stamps {
  std::once_flag taken;  // calls on several threads may share a source
  std::vector<std::optional<FileStamp>> files;
};

void DataSource::stamp() const {
  if (stamps_) std::call_once(stamps_->taken, [&] { stamps_->files = stamps_of(paths()); });
}

void DataSource::check_unchanged() const {
  if (!stamps_) return;
  stamp();
  const std::vector<std::string> files = paths();
  const std::vector<std::optional<FileStamp>> now = stamps_of(files);
  for (std::size_t f = 0; f < files.size(); ++f) {
    const std::optional<FileStamp>& before = stamps_->files[f];
    if (!before || now[f] == before) continue;
    std::string what = "it was replaced or removed";
    if (now[f] && now[f]->inode == before->inode) {
      what = now[f]->size == before->size ? "it was written to"
                                          : "its size went from " + std::to_string(before->size) +
                                                " to " + std::to_string(now[f]->size) + " bytes";
    }
    throw Error((files.size() == 1 ? name_ : files[f]) + ": the file changed while it was read (" +
                what + "): read it when it is complete");
  }
}

DataSource DataSource::file(std::string path) {
  // A pipe (a FIFO, /dev/stdin, a shell's <(...)) can be read only once, and every pass opens
  // the source again: it is stored like standard input.
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (!error && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status) &&
      !std::filesystem::is_directory(status)) {
    const data::File in(std::fopen(path.c_str(), "rb"));
    if (!in) throw Error(path + ": cannot open the data file: " + std::strerror(errno));
    return stored(in.get(), path, kStoredLimit);
  }
  DataSource source;
  source.name_ = std::move(path);
  source.stamps_ = std::make_shared<Stamps>();
  return source;
}

DataSource DataSource::files(std::vector<std::string> paths) {
  if (paths.empty()) throw UsageError("no data files");
  if (paths.size() == 1) return file(std::move(paths.front()));
  DataSource source;
  source.name_ = paths.front() + " and " + std::to_string(paths.size() - 1) +
                 (paths.size() == 2 ? " more file" : " more files");
  source.paths_ = std::move(paths);
  source.stamps_ = std::make_shared<Stamps>();
  return source;
}

DataSource DataSource::memory(MemoryData data) {
  DataSource source;
  source.name_ = data.name;
  source.memory_ = std::move(data);
  return source;
}

DataSource DataSource::standard_input(std::uint64_t limit) {
  return stored(stdin, "<stdin>", limit);
}

DataSource DataSource::stored(std::FILE* in, const std::string& name, std::uint64_t limit) {
  const auto failed = [&](const std::string& why) {
    return Error(name + ": cannot store the data in a temporary file: " + why);
  };
  std::string path = (std::filesystem::temp_directory_path() / "momentid_stream_XXXXXX").string();
  const int fd = data::create_temporary(path, data::Temporary::kStored);
  if (fd < 0) throw failed(std::strerror(errno));
  // Removed when the last copy of the source is gone.
  auto stored = std::shared_ptr<const std::string>(new std::string(path), [](const std::string* p) {
    data::forget_temporary(data::Temporary::kStored);
    std::remove(p->c_str());
    delete p;
  });
  data::File out(fdopen(fd, "wb"));
  if (!out) {
    ::close(fd);
    throw failed(std::strerror(errno));
  }
  std::vector<char> buffer(1 << 20);
  std::uint64_t total = 0;
  for (;;) {
    const std::size_t got = std::fread(buffer.data(), 1, buffer.size(), in);
    total += got;
    if (total > limit) {
      throw Error(name + ": more than " + std::to_string(limit) +
                  " bytes arrived, the most stored from a stream (the limit keeps an endless "
                  "stream from filling the disk): give the data as a file, or a larger limit "
                  "(--stdin-limit)");
    }
    if (got > 0 && std::fwrite(buffer.data(), 1, got, out.get()) != got) {
      throw failed(std::strerror(errno));
    }
    if (got < buffer.size()) break;
  }
  if (std::ferror(in)) throw Error(name + ": cannot read the data: " + std::strerror(errno));
  if (std::fclose(out.release()) != 0) throw failed(std::strerror(errno));
  DataSource source;
  source.name_ = name;
  source.stored_ = std::move(stored);
  source.stamps_ = std::make_shared<Stamps>();
  return source;
}

std::unique_ptr<DataReader> DataSource::open(const ColumnRequest& request) const {
  stamp();
  return data::open_sums(request, name_, [&](const ColumnRequest& r) {
    if (memory_) return data::open_memory(*memory_, r);
    if (!paths_.empty()) return data::open_chain(paths_, r);
    if (stored_) return DataReader::open(*stored_, r, name_);
    return DataReader::open(name_, r);
  });
}

std::vector<std::string> DataSource::paths() const {
  if (memory_) return {};
  if (!paths_.empty()) return paths_;
  return {stored_ ? *stored_ : name_};
}

std::vector<DataSource::Shard> DataSource::shards(std::size_t bytes) const {
  stamp();
  bytes = std::max<std::size_t>(bytes, 1);
  const auto cut = [&](std::uint64_t size) {
    return static_cast<std::size_t>(std::max<std::uint64_t>(1, (size + bytes - 1) / bytes));
  };
  std::vector<Shard> out;
  const auto add = [&](std::size_t file, std::size_t count) {
    for (std::size_t k = 0; k < count; ++k) out.push_back({file, k, count});
  };
  if (memory_) {
    add(0,
        cut(std::uint64_t{8} * memory_->rows * std::max<std::size_t>(1, memory_->columns.size())));
    return out;
  }
  const std::vector<std::string> files = paths();
  for (std::size_t f = 0; f < files.size(); ++f) {
    // A file that cannot be sized is one shard, and its reader says what is wrong with it. A
    // .mat file is one too: matio reads a variable whole, so every shard would read it all.
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(files[f], error);
    std::array<char, data::kDetectBytes> start{};
    std::size_t got = 0;
    if (data::File file{std::fopen(files[f].c_str(), "rb")}) {
      got = std::fread(start.data(), 1, start.size(), file.get());
    }
    const bool whole = data::is_mat(std::string_view(start.data(), got));
    add(f, error || whole ? 1 : cut(size));
  }
  return out;
}

std::unique_ptr<DataReader> DataSource::open(const Shard& shard, ColumnRequest request) const {
  request.part.index = shard.index;
  request.part.count = shard.count;
  stamp();
  return data::open_sums(request, name_, [&](const ColumnRequest& r) {
    if (memory_) return data::open_memory(*memory_, r);
    if (!paths_.empty()) return DataReader::open(paths_.at(shard.file), r);
    if (stored_) return DataReader::open(*stored_, r, name_);
    return DataReader::open(name_, r);
  });
}

}  // namespace momentid
