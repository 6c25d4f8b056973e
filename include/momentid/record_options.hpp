#pragma once
// How to read a record: the options that identify, check and validate share, and that one pass
// over the data takes. In a header of its own rather than in reader.hpp because it sits a level
// above the reader: it names model variables (validate() needs the model) and says how a pass
// runs (threads, shards, progress), which a reader of one file never sees.

#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "momentid/reader.hpp"
#include "momentid/types.hpp"

namespace momentid {

class Model;

// How a pass reads its data: on how many threads, in shards of what size, with what report of
// its progress.
struct PassControl {
  // Threads reading at once: 0 for the machine's cores. Files, and shards of large files, are
  // read in parallel (see moments_from_data).
  std::size_t threads = 0;
  // Files are cut into shards of about this many bytes (DataSource::shards).
  std::size_t shard_bytes = kDefaultShardBytes;
  static constexpr std::size_t kDefaultShardBytes = std::size_t{16} << 20;
  // In an MPI job (momentid built with MOMENTID_MPI, MPI started): every process of the job
  // takes part in each pass, reading a contiguous range of the shards, and every process gets
  // the whole result. Every process must then make the same passes.
  bool across_processes = false;
  // Called a few times a second with the rows read so far and the fraction of the data read,
  // when known (e.g. to show progress); none: nothing is called.
  std::function<void(std::size_t rows, std::optional<double> fraction)> progress;
  // Runs `read`, the reading of a pass, which touches only the data and the pass's own state;
  // none: it is called directly. A front end that holds a lock the reading does not need
  // releases it here (the Python module, its GIL: the rest of a call uses GiNaC, which other
  // threads must not use meanwhile).
  std::function<void(const std::function<void()>& read)> around_pass;
  // Asked about ten times a second, on the calling thread, while a pass reads (inside
  // around_pass): true stops the pass, which then throws Interrupted once the shards being read
  // are done. A front end answers whether the user pressed Ctrl-C. None: never asked.
  std::function<bool()> interrupted;
};

// Where a record's channels are, how it is laid out and sampled, and how a pass reads it: a
// member `record` of IdentifyOptions, CheckOptions, ReplayOptions (validate) and DataOptions.
// Every command reads columns, dt and layout. identify and check use every field; validate (and
// simulate --input-file) ignore `hold`, because they interpolate the inputs between samples
// (ReplayOptions::interpolation), and `control`, because they read the record once, whole, on
// one thread.
//
// Example:
//   IdentifyOptions options;
//   options.record.columns = {{"v", "velocity"}, {"t", "time"}};
//   options.record.dt = 0.01;
struct RecordOptions {
  // Model variable (or `t`, the time) -> data column, for data whose columns have other names.
  std::map<std::string, std::string> columns;
  // The sample interval, overriding the data's: the time column is then not read. Within
  // [kMinInterval, kMaxInterval], where the equations' powers of it (up to dt^-8) stay normal
  // numbers.
  std::optional<double> dt;
  static constexpr double kMinInterval = 1e-12;
  static constexpr double kMaxInterval = 1e12;
  // How the file departs from the usual layout: units rows, decimal comma, missing values, ...
  FileLayout layout;
  // How the inputs were sampled; nullopt: the data's `input-hold` metadata, else kSample.
  std::optional<InputHold> hold;
  // Threads, shards and progress of each pass over the data.
  PassControl control;

  // Throws UsageError for a dt that is not a positive finite number or outside [kMinInterval,
  // kMaxInterval] ("dt") and, with a model,
  // for a column mapped from a name that is neither `t` nor a state or input of the model
  // ("columns").
  void validate(const Model* model) const;
  // Throws DataError at `where` for a record's own interval `dt` (its time column, metadata or
  // stored interval) outside [kMinInterval, kMaxInterval], where validate() refuses a --dt.
  static void check_record_interval(double dt, const SourceLocation& where);
};

// `model` with the columns that `record.columns` maps from a state's derivative (v' or y'', as
// in `--columns "v'=accel"`) declared as a `measured` statement would: each such key becomes the
// variable of that column, the one the model file declares for that derivative, else a new one
// named after the column (or the state and `_dot` when that name is not free). Throws
// UsageError ("columns") for a key that is not a state's first or second derivative, with the
// message the `measured` statement would get.
Model declare_derivative_columns(const Model& model, RecordOptions& record);
// The same, first adding the columns that the metadata of `source` declare (`measured.a=v'`, as
// simulate writes them and convert keeps them) for each derivative that neither the model nor
// `record.columns` gives a column.
Model declare_derivative_columns(const Model& model, RecordOptions& record,
                                 const DataSource& source);

}  // namespace momentid
