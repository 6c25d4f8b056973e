#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "momentid/metadata.hpp"
#include "momentid/types.hpp"

namespace momentid {

// A file written whole or not at all: the bytes go to a temporary file beside the target, which
// commit() renames into place; an OutputFile destroyed without commit() removes it. The path "-"
// is standard output; a device or a pipe is written to directly; through a symbolic link, its
// target is replaced. Throws Error when the file cannot be created.
class OutputFile {
 public:
  explicit OutputFile(const std::string& path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  void write(const char* data, std::size_t size);
  // Flushes, closes and moves the file into place. Throws Error if anything failed.
  void commit();

 private:
  // Marks the output failed, keeping the first failure's errno for the message.
  void fail();
  // ": <the first failure's cause>", or empty.
  std::string reason() const;

  std::string path_, temporary_;
  std::FILE* file_ = nullptr;
  bool failed_ = false;
  int error_ = 0;
  bool direct_ = false;  // writing straight to a device or pipe, not through a temporary file
};

// Writes `contents` to `path` as an OutputFile does.
void write_whole_file(const std::string& path, const std::string& contents);

// Writes a data file in the layouts DataReader reads (CSV or binary, see data.hpp), whole or not
// at all (an OutputFile): a writer destroyed without commit() leaves nothing.
//
// Example:
//   DataMetadata metadata;
//   metadata.add_line({{"dt", "0.01"}});
//   DataWriter out("d.csv", DataWriter::Format::kCsv, metadata, {"t", "y", "x"});
//   out.row(values);  // one double per column
//   out.commit();
class DataWriter {
 public:
  using Format = WriterFormat;

  DataWriter(const std::string& path, Format format, const DataMetadata& metadata,
             const std::vector<std::string>& columns);
  ~DataWriter();
  DataWriter(const DataWriter&) = delete;
  DataWriter& operator=(const DataWriter&) = delete;

  // One value per column. CSV numbers are the shortest text that reads back exactly.
  void row(const double* values);
  // Flushes, closes and moves the file into place. Throws Error if anything failed.
  void commit();

 private:
  void flush();

  OutputFile file_;
  Format format_;
  std::size_t columns_;
  std::vector<char> buffer_;
  std::size_t used_ = 0;
};

// Makes SIGINT, SIGTERM and SIGHUP delete the temporary file an OutputFile is filling, and the
// one a stream is stored in (DataSource::standard_input), before the process ends, so that an
// interrupted run leaves nothing behind. For programs that write files or read streams.
void remove_partial_output_on_interrupt();

}  // namespace momentid
