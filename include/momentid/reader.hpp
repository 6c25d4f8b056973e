#pragma once

#include <cstddef>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "momentid/error.hpp"
#include "momentid/metadata.hpp"
#include "momentid/types.hpp"

namespace momentid {

// How a file departs from the usual layout (docs/data-files.md, "Data from the lab").
struct FileLayout {
  // Lines after the header row that are not data (units, descriptions), skipped.
  std::size_t skip_rows = 0;
  // The decimal separator, '.' or ','; ',' needs a field separator other than the comma.
  char decimal = '.';
  MissingValues missing = MissingValues::kError;
  // The sample interval from a scalar stored in the file (.mat, HDF5): `Ts`, or `1/fs` for a
  // rate; checked against the time column when there is one.
  std::optional<std::string> dt_from;
  // Names for the columns of a file that has none (a 2-D .npy array), in order.
  std::vector<std::string> column_names;
  // Several runs in one .mat or HDF5 file: each prefix, put in front of every channel's name
  // (`run1/` reads `run1/y` for `y`, `a_` reads `a_y`), names one run's channels.
  std::vector<std::string> runs;
};

// The rows a reader dropped for missing values: how many, the first one's place, and at how
// many places within a run a new run began after them (MissingValues::kSplitRun) or their
// neighbours were joined (MissingValues::kDropRow).
struct MissingSummary {
  std::size_t rows = 0;
  std::optional<SourceLocation> first;
  std::size_t splits = 0;
  std::size_t joins = 0;

  // Adds what a later part of the record dropped.
  void add(const MissingSummary& later);
};

// What to read from a data file: the columns to deliver, in this order (normally the model's
// states, then its inputs), and where a column has another name in the file (`--columns
// v=velocity` maps the model's `v` to the file's `velocity`). Through DataSource::open, a name
// may map to a sum of columns with constant factors (column_sum): `--columns
// "z''=acc_mass-acc_table"`.
struct ColumnRequest {
  std::vector<std::string> names;
  std::map<std::string, std::string> rename;
  // Fewer data rows than this is an error naming the file (the estimation needs them).
  std::size_t min_rows = 2;
  // The sample interval, overriding the data's: the time column is then neither read nor
  // checked, and time_step() returns it.
  std::optional<double> dt;

  FileLayout layout;

  // Part `index` of `count` parts of the file, cut at row boundaries (a CSV file by bytes, at
  // line starts; the other formats by rows): the reader delivers up to `before` rows before the
  // part, its own rows, then up to `after` rows past it (see DataBlock::zone), and stops. The
  // rows before and after are those of the neighbouring parts, read as context; row counts,
  // time steps and min_rows concern the part's own rows only (min_rows is not checked).
  // count == 1: the whole file.
  struct Part {
    std::size_t index = 0, count = 1;
    std::size_t before = 0, after = 0;
  };
  Part part;
};

// Where the rows of a block lie with respect to the part a reader was opened on
// (ColumnRequest::part): before it, in it, or past it.
enum class RowZone { kBefore, kOwned, kAfter };

// Consecutive rows of one run (one continuous record). A block never spans two runs.
struct DataBlock {
  std::vector<double> values;  // row-major, rows() x ColumnRequest::names.size()
  std::size_t rows = 0;
  long run = 0;                    // the `run` column's value, 0 when the file has none
  bool run_starts = false;         // the first block of a run
  RowZone zone = RowZone::kOwned;  // a block never spans two zones
};

// Streams a data file in blocks, so that memory does not grow with its length. Two layouts:
//
// CSV: optional `# momentid: ...` metadata lines (and other `#` comment lines) before a header
// row of column names; then one row per sample. The separator is taken from the header: comma,
// else semicolon, else blanks. An optional time column holds the sample times (uniform steps
// within a run): `t`, or else the first named `time` in any case, either optionally followed by
// a unit in brackets or parentheses (`t [s]`, `Time (s)`), or the one ColumnRequest::rename maps
// `t` to. Steps may differ from the first by 1e-6 of it plus 2.4e-7 of |t|, the rounding of
// float32 time stamps; time_step() is the mean step. An optional `run` column (integers)
// separates records; other columns not requested are ignored. A UTF-8 byte order mark and CR LF
// line ends are accepted.
//
// Binary (docs/data-files.md, "Binary"): the 8 bytes `MOMNTID1`, a little-endian uint32 H, H bytes
// of text holding the metadata lines and the header row exactly as in CSV, then the rows as
// little-endian IEEE-754 float64 values, one per column.
//
// Every problem throws DataError located at the file line and column (binary: the row number as
// line, the column number as column) with what was found and what was expected.
//
// Example:
//   auto reader = DataReader::open("d.csv", {.names = {"y", "v", "x"}});
//   DataBlock block;
//   while (reader->next(block, 65536)) accumulate(block);
class DataReader {
 public:
  // Opens a file, choosing the format by its first bytes (not by its name); messages name it
  // `name` when given.
  static std::unique_ptr<DataReader> open(const std::string& path, const ColumnRequest& request,
                                          const std::string& name = "");
  virtual ~DataReader() = default;

  virtual const DataMetadata& metadata() const = 0;
  // The column names of the file's header, in file order.
  virtual const std::vector<std::string>& columns() const = 0;
  // Arrays of the file that are not columns (text, integer or complex values, or values never
  // written), each with the reason: requesting one by name fails with it.
  virtual std::map<std::string, std::string> unusable_columns() const { return {}; }
  // The sample interval: ColumnRequest::dt when given; else the metadata's `dt` (the time
  // column's first step is checked against it); else the mean step of the time column over the
  // rows read so far, final once every row has been read; else none.
  virtual std::optional<double> time_step() const = 0;
  // Reads up to `max_rows` rows into `block`; false (and block.rows == 0) at the end.
  virtual bool next(DataBlock& block, std::size_t max_rows) = 0;
  // Data rows delivered so far.
  virtual std::size_t rows_read() const = 0;
  // Rows dropped so far for missing values (FileLayout::missing).
  virtual const MissingSummary& missing() const = 0;
  // How much of the data has been read, from 0 to 1, when the reader can tell.
  virtual std::optional<double> fraction_read() const { return std::nullopt; }

  // The time steps of the rows delivered so far (steps to a part's own rows only): how many
  // there are and their sum. A reader whose interval comes from elsewhere (ColumnRequest::dt,
  // the metadata) has none. time_step() is their mean.
  struct Steps {
    std::size_t count = 0;
    double sum = 0;
  };
  virtual Steps steps() const { return {}; }
};

// Columns held in memory by the caller, e.g. numpy arrays: no copy is made, so the values must
// outlive every reader opened on them. Column c's value in row r is
// `columns[c].values[r * columns[c].stride]`. The names follow the CSV rules: `t` holds the
// sample times and `run` separates records; `metadata` may give `dt` and `input-hold`. Errors
// are located at `name`, the row (from 1) as line and the column (from 1) as column.
struct MemoryColumn {
  std::string name;
  const double* values = nullptr;
  std::size_t stride = 1;
};
struct MemoryData {
  std::vector<MemoryColumn> columns;
  std::size_t rows = 0;
  DataMetadata metadata;
  std::string name = "<memory>";
};

// A channel formed from columns: the sum of factor × column over its terms.
struct ColumnSum {
  struct Term {
    double factor = 1;
    std::string column;
  };
  std::vector<Term> terms;
};

// What ColumnRequest::rename's `variable=text` maps to, given the record's `columns`: nullopt
// when `text` is a column (or has no operator or blank, or `variable` is the time `t`), else the
// sum `text` writes: terms joined by `+` or `-`, each a column with an optional factor
// (`2.5*a`, `a*2.5`), a column holding blanks or operators in quotes (`'Acc 1' - 'Acc 2'`).
// Throws UsageError ("columns", naming `source`) for a sum that does not parse or a column
// that `columns` lacks.
std::optional<ColumnSum> column_sum(const std::string& variable, const std::string& text,
                                    const std::vector<std::string>& columns,
                                    const std::string& source);

// Where the data of an identification come from: a file (any format DataReader::open reads) or
// columns in memory. A source is opened once per pass, with the columns the pass needs. It
// stands for its files as they are when it is first opened (and its copies with it): a pass
// that finds one changed since is an error (check_unchanged), so that the passes of one call
// read one record; make a new source to read a file that has changed.
//
// Example:
//   DataSource source = DataSource::file("d.csv");
//   auto reader = source.open({.names = {"y", "x"}});
class DataSource {
 public:
  // A file; a pipe or a device (a FIFO, /dev/stdin, a shell's <(...)) is read to its end now,
  // as standard_input() is, and keeps its path in messages.
  static DataSource file(std::string path);
  // Several files, read one after the other as one record of many runs: a file's runs are
  // never joined to the next file's. The files may be of different formats, and must have the
  // requested columns and the same sample interval (DataError at the first that does not).
  // One path is file().
  static DataSource files(std::vector<std::string> paths);
  static DataSource memory(MemoryData data);
  // Standard input, read to its end now into a temporary file that the source (and its copies)
  // owns and removes (also when a signal ends the program, with
  // remove_partial_output_on_interrupt()); named `<stdin>` in messages. Throws Error when it
  // cannot be stored, or when more than `limit` bytes arrive (an endless stream would fill the
  // disk).
  static DataSource standard_input(std::uint64_t limit = kStoredLimit);
  static constexpr std::uint64_t kStoredLimit = std::uint64_t{16} << 30;  // 16 GiB

  // The path (the first and how many more, for several), or MemoryData::name.
  const std::string& name() const { return name_; }
  std::unique_ptr<DataReader> open(const ColumnRequest& request) const;

  // A shard of the source that a reader of its own can read (ColumnRequest::Part): part
  // `index` of the `count` parts of file `file` (of paths()).
  struct Shard {
    std::size_t file = 0;
    std::size_t index = 0, count = 1;
  };
  // The source cut into shards in record order: each file into parts of about `bytes` bytes
  // (at least one; a .mat file, whose variables are read whole, is one), columns in memory into
  // parts of about `bytes` bytes of values. The cut depends on the sizes and formats only, so
  // that every reader of the source cuts it alike.
  std::vector<Shard> shards(std::size_t bytes) const;
  // A reader of one shard, rows as ColumnRequest::part says (its index and count are the
  // shard's).
  std::unique_ptr<DataReader> open(const Shard& shard, ColumnRequest request) const;
  // The files read (one for a file or standard input), none for columns in memory.
  std::vector<std::string> paths() const;
  // Throws Error naming the file when a file of the source is not as it was when the source was
  // first opened (its size, modification time or inode changed: an acquisition still writing
  // it, a copy over it), as the rows read would be a mixture or cut short. Each pass calls it
  // when it has read.
  void check_unchanged() const;

 private:
  struct Stamps;  // the files' sizes, modification times and inodes when first opened
  // Takes the stamps, the first time.
  void stamp() const;
  // `in` read to its end into a temporary file that the source owns, named `name`.
  static DataSource stored(std::FILE* in, const std::string& name, std::uint64_t limit);

  std::string name_;
  std::optional<MemoryData> memory_;
  std::shared_ptr<const std::string> stored_;  // the file standard input or a pipe was stored in
  std::vector<std::string> paths_;             // several files
  std::shared_ptr<Stamps> stamps_;             // for files, shared by the copies
};

}  // namespace momentid
