#include "momentid/writer.hpp"

#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "data/array_writers.hpp"
#include "data/format.hpp"
#include "data/header.hpp"
#include "data/temporary.hpp"
#include "momentid/error.hpp"

namespace momentid {
namespace {

constexpr std::size_t kBufferSize = 1 << 20;

}  // namespace

OutputFile::OutputFile(const std::string& path) : path_(path) {
  std::error_code error;
  const auto status = std::filesystem::status(path_, error);
  if (path_ == "-") {
    file_ = stdout;
  } else if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    // A device or a pipe is written to directly: renaming onto it would replace it.
    file_ = std::fopen(path_.c_str(), "wb");
    if (file_ == nullptr) {
      throw Error(path_ + ": cannot write the output: " + std::strerror(errno));
    }
    direct_ = true;
  } else {
    // Through a symbolic link, the file it points to is replaced, not the link.
    for (int hops = 0; hops < 40; ++hops) {
      const std::filesystem::path link(path_);
      if (!std::filesystem::is_symlink(std::filesystem::symlink_status(link, error))) break;
      const std::filesystem::path target = std::filesystem::read_symlink(link, error);
      path_ = (target.is_absolute() ? target : link.parent_path() / target).string();
    }
    temporary_ = path_ + ".partial-XXXXXX";
    const int fd = data::create_temporary(temporary_);
    if (fd < 0) throw Error(path_ + ": cannot create the output file: " + std::strerror(errno));
    file_ = fdopen(fd, "wb");
    if (file_ == nullptr) {
      ::close(fd);
      std::remove(temporary_.c_str());
      data::forget_temporary();
      throw Error(path_ + ": cannot write the output file: " + std::strerror(errno));
    }
  }
}

OutputFile::~OutputFile() {
  if (file_ != nullptr && file_ != stdout) {
    std::fclose(file_);
    if (!direct_) std::remove(temporary_.c_str());
  }
  data::forget_temporary();
}

void OutputFile::write(const char* data, std::size_t size) {
  if (size > 0 && std::fwrite(data, 1, size, file_) != size) fail();
}

void OutputFile::fail() {
  if (!failed_) error_ = errno;
  failed_ = true;
}

std::string OutputFile::reason() const {
  return error_ != 0 ? std::string(": ") + std::strerror(error_) : std::string();
}

void OutputFile::commit() {
  if (std::fflush(file_) != 0 || std::ferror(file_)) fail();
  if (file_ == stdout) {
    if (failed_) throw Error("cannot write to standard output" + reason());
    return;
  }
  if (std::fclose(file_) != 0) fail();
  file_ = nullptr;
  if (direct_) {
    if (failed_) throw Error(path_ + ": writing the output failed" + reason());
    return;
  }
  if (failed_) {
    std::remove(temporary_.c_str());
    throw Error(path_ + ": writing the output file failed" + reason());
  }
  // mkstemp creates the file readable by its owner only; give it the usual permissions.
  std::error_code ignored;
  std::filesystem::permissions(
      temporary_,
      std::filesystem::perms::owner_read | std::filesystem::perms::owner_write |
          std::filesystem::perms::group_read | std::filesystem::perms::others_read,
      ignored);
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    std::remove(temporary_.c_str());
    data::forget_temporary();
    throw Error(path_ + ": cannot move the output file into place: " + reason);
  }
  data::forget_temporary();
}

void write_whole_file(const std::string& path, const std::string& contents) {
  OutputFile out(path);
  out.write(contents.data(), contents.size());
  out.commit();
}

DataWriter::DataWriter(const std::string& path, Format format, const DataMetadata& metadata,
                       const std::vector<std::string>& columns, std::optional<std::size_t> rows)
    : path_(path), format_(format), columns_(columns), metadata_(metadata), rows_(rows) {
  if (format_ == Format::kCsv || format_ == Format::kBinary) {
    file_ = std::make_unique<OutputFile>(path);
    buffer_.resize(kBufferSize);
    // The header goes through the buffer like the rows: on standard output nothing appears
    // before the first megabyte or commit(), so a run that fails early leaves no header-only
    // output.
    std::string header = data::header_text(metadata, columns);
    if (format_ == Format::kBinary) {
      const auto length = static_cast<std::uint32_t>(header.size());
      const char bytes[4] = {static_cast<char>(length), static_cast<char>(length >> 8),
                             static_cast<char>(length >> 16), static_cast<char>(length >> 24)};
      header = std::string(data::kMagic) + std::string(bytes, 4) + header;
    }
    if (header.size() > buffer_.size()) buffer_.resize(header.size() + kBufferSize);
    std::copy(header.begin(), header.end(), buffer_.begin());
    used_ = header.size();
    return;
  }
  if (path == "-" && format_ != Format::kNpy) {
    throw UsageError("standard output takes csv, bin or npy, not " + to_string(format_) +
                     ", whose file is written whole before it is moved into place: name a file");
  }
  if (!rows) throw std::invalid_argument("DataWriter: an array format needs the row count");
  switch (format_) {
    case Format::kNpy:
      array_ = data::open_npy_writer(path, columns.size(), *rows);
      break;
    case Format::kMat5:
    case Format::kMat73:
      array_ = data::open_mat_writer(path, columns, metadata, *rows, format_ == Format::kMat73);
      break;
    default:
      array_ = data::open_hdf5_writer(path, columns, metadata, *rows);
      break;
  }
  // Blocks of at most 2^16 rows (HDF5's chunk) and 2^20 values (a wide record's bound).
  const std::size_t width = std::max<std::size_t>(columns.size(), 1);
  block_.reserve(std::max<std::size_t>(1, std::min<std::size_t>(1 << 16, (1 << 20) / width)) *
                 width);
}

DataWriter::~DataWriter() = default;

void DataWriter::flush() {
  file_->write(buffer_.data(), used_);
  used_ = 0;
}

void DataWriter::flush_block() {
  array_->rows(block_.data(), block_.size() / std::max<std::size_t>(columns_.size(), 1));
  block_.clear();
}

void DataWriter::rows(const double* values, std::size_t count) {
  const std::size_t width = columns_.size();
  if (rows_ && count > *rows_ - written_) {
    throw std::invalid_argument("DataWriter: more rows than the " + std::to_string(*rows_) +
                                " announced");
  }
  written_ += count;
  if (array_) {
    for (std::size_t r = 0; r < count; ++r) {
      if (block_.size() + width > block_.capacity()) flush_block();
      block_.insert(block_.end(), values + r * width, values + (r + 1) * width);
    }
    return;
  }
  for (std::size_t r = 0; r < count; ++r, values += width) {
    if (buffer_.size() - used_ < width * 32 + 2) flush();
    char* out = buffer_.data() + used_;
    if (format_ == Format::kBinary) {
      for (std::size_t c = 0; c < width; ++c) {
        std::uint64_t bits = std::bit_cast<std::uint64_t>(values[c]);
        for (int b = 0; b < 8; ++b) *out++ = static_cast<char>(bits >> (8 * b));
      }
    } else {
      char* const end = buffer_.data() + buffer_.size();
      for (std::size_t c = 0; c < width; ++c) {
        if (c) *out++ = ',';
        out = std::to_chars(out, end, values[c]).ptr;
      }
      *out++ = '\n';
    }
    used_ = static_cast<std::size_t>(out - buffer_.data());
  }
}

void DataWriter::commit() {
  if (rows_ && written_ != *rows_) {
    throw std::invalid_argument("DataWriter: " + std::to_string(written_) + " rows written, " +
                                std::to_string(*rows_) + " announced");
  }
  if (array_) {
    if (!block_.empty()) flush_block();
    array_->commit();
    return;
  }
  flush();
  file_->commit();
}

std::optional<std::string> DataWriter::note() const {
  if (format_ != Format::kNpy) return std::nullopt;
  std::string names;
  for (const std::string& c : columns_) names += (names.empty() ? "" : ",") + c;
  std::string options = " with --names " + names;
  const bool has_time = std::any_of(columns_.begin(), columns_.end(), [](const std::string& c) {
    return c == "t" || data::is_time_name(c);
  });
  if (const auto dt = metadata_.get("dt"); dt && !has_time) options += " --dt " + *dt;
  if (const auto hold = metadata_.get("input-hold");
      hold && (*hold == "zoh" || *hold == "sample")) {
    options += " --input-hold " + *hold;
  }
  return "a .npy file keeps neither column names nor metadata: read " + path_ + options;
}

// The temporary files, for remove_partial_output_on_interrupt() to delete from a signal
// handler: fixed buffers, since a handler may not allocate.
namespace {
struct Remembered {
  char path[4096];
  volatile std::sig_atomic_t set = 0;
};
Remembered g_temporaries[2];  // by data::Temporary

Remembered& remembered(data::Temporary which) {
  return g_temporaries[which == data::Temporary::kOutput ? 0 : 1];
}

extern "C" void remove_and_reraise(int signal) {
  for (const Remembered& t : g_temporaries) {
    if (t.set) ::unlink(t.path);
  }
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}
}  // namespace

namespace data {

void remember_temporary(const std::string& path, Temporary which) {
  Remembered& t = remembered(which);
  if (path.size() < sizeof t.path) {
    t.set = 0;
    std::memcpy(t.path, path.c_str(), path.size() + 1);
    t.set = 1;
  }
}

void forget_temporary(Temporary which) { remembered(which).set = 0; }

int create_temporary(std::string& path, Temporary which) {
  // An interrupt between creating the file and remembering it would leave the file behind: the
  // signals that remove it are held until it is remembered.
  sigset_t interrupts, previous;
  sigemptyset(&interrupts);
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&interrupts, signal);
  pthread_sigmask(SIG_BLOCK, &interrupts, &previous);
  const int fd = mkstemp(path.data());
  const int error = errno;
  if (fd >= 0) remember_temporary(path, which);
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  errno = error;
  return fd;
}

}  // namespace data

void remove_partial_output_on_interrupt() {
  std::signal(SIGINT, remove_and_reraise);
  std::signal(SIGTERM, remove_and_reraise);
  std::signal(SIGHUP, remove_and_reraise);
}

}  // namespace momentid
