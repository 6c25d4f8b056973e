#pragma once

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "momentid/metadata.hpp"
#include "momentid/types.hpp"

namespace momentid {

namespace data {
class ArrayWriter;
}  // namespace data

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

// Writes a data file a row at a time in any format `momentid convert` writes (FileFormat): CSV
// and binary as DataReader reads them (data-files.md), NumPy .npy, MATLAB .mat (levels 5 and 7.3)
// and HDF5 with the column names and metadata each format keeps (see note()). Whole or not at
// all: a writer destroyed without commit() leaves nothing, neither the file nor a temporary one.
//
// Example:
//   DataMetadata metadata;
//   metadata.add_line({{"dt", "0.01"}});
//   DataWriter out("d.h5", FileFormat::kHdf5, metadata, {"t", "y", "x"}, 1000);
//   out.row(values);  // one double per column, 1000 times
//   out.commit();
class DataWriter {
 public:
  using Format = FileFormat;

  // `rows`: how many rows will be written. The array formats (.npy, .mat, HDF5) give their
  // length before their values and need it; CSV and binary check it when it is given. Throws
  // Error when the file cannot be created, UsageError for a .mat or HDF5 file on standard
  // output ("-"), which those formats cannot stream, and std::invalid_argument for an array
  // format without `rows`.
  DataWriter(const std::string& path, Format format, const DataMetadata& metadata,
             const std::vector<std::string>& columns,
             std::optional<std::size_t> rows = std::nullopt);
  ~DataWriter();
  DataWriter(const DataWriter&) = delete;
  DataWriter& operator=(const DataWriter&) = delete;

  // One value per column. CSV numbers are the shortest text that reads back exactly.
  void row(const double* values) { rows(values, 1); }
  // `count` rows, row-major. Throws std::invalid_argument past the `rows` announced.
  void rows(const double* values, std::size_t count);
  // Flushes, closes and moves the file into place. Throws Error if anything failed, and
  // std::invalid_argument when fewer rows were written than announced.
  void commit();

  // What the file cannot tell its reader: a .npy file keeps neither column names nor metadata,
  // so the note gives the options that read it back as written ("a .npy file keeps neither
  // column names nor metadata: read d.npy with --names t,y,x --input-hold zoh"; `--dt` when no
  // column is a time). Nothing for the other formats.
  std::optional<std::string> note() const;

 private:
  void flush();
  void flush_block();

  std::string path_;
  Format format_;
  std::vector<std::string> columns_;
  DataMetadata metadata_;
  std::optional<std::size_t> rows_;
  std::size_t written_ = 0;
  // CSV and binary: text or bytes, a megabyte at a time.
  std::unique_ptr<OutputFile> file_;
  std::vector<char> buffer_;
  std::size_t used_ = 0;
  // The array formats: rows gathered into blocks, each handed over at once.
  std::unique_ptr<data::ArrayWriter> array_;
  std::vector<double> block_;
};

// Makes SIGINT, SIGTERM and SIGHUP delete the temporary file an OutputFile is filling, and the
// one a stream is stored in (DataSource::standard_input), before the process ends, so that an
// interrupted run leaves nothing behind. For programs that write files or read streams.
void remove_partial_output_on_interrupt();

}  // namespace momentid
