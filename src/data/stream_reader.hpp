#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "data/header.hpp"
#include "data/time_precision.hpp"
#include "momentid/reader.hpp"

namespace momentid::data {

// A run number must be an integer that fits a long.
bool to_run(double value, long& run);

// The time and run of a row.
struct RowKeys {
  double t = 0;
  long run = 0;
  // The first requested field of the row that holds a missing value, or -1.
  int missing_field = -1;
};

// The hint of an error at a missing value, naming the option (FileLayout::missing) that passes
// over it.
inline std::string missing_value_hint() {
  return "a missing value? " + UsageError::mention("missing") +
         " drop-row or split-run passes over it";
}

// The reading both layouts share: blocks, runs and the time-step checks. A layout delivers rows
// through read_row() and says where a field is for errors.
class StreamReader : public DataReader {
 public:
  const DataMetadata& metadata() const override { return header_.metadata; }

  const std::vector<std::string>& columns() const override { return header_.names; }

  std::optional<double> time_step() const override;

  std::size_t rows_read() const override { return rows_read_; }

  const MissingSummary& missing() const override { return missing_; }

  bool next(DataBlock& block, std::size_t max_rows) override;

  Steps steps() const override {
    if (request_.dt || header_.metadata_dt) return {};
    return {steps_, span_};
  }

 protected:
  StreamReader(std::string path, const ColumnRequest& request)
      : path_(std::move(path)), request_(request) {}

  // Reads the next data row: the requested values into `row` (in request order), its time and
  // run into `keys`. False at the end of the data. A missing value in a requested field fails
  // when the rule is MissingValues::kError, else marks the row in `keys` (pass_over_missing).
  virtual bool read_row(double* row, RowKeys& keys) = 0;
  // For a layout that numbers its rows and sets takes_many_rows_: reads up to `count` rows at once,
  // their requested values into `rows` (request order, as read_row) and their times into `times`
  // when the file has a time column, and returns how many: 0 at the end of the data, or before a
  // row that read_row must take (a value that is not finite, a row cut short). The rows follow
  // the last one read.
  virtual std::size_t read_rows(double* /*rows*/, double* /*times*/, std::size_t /*count*/) {
    return 0;
  }
  // Takes back the last `count` rows of read_rows(), to be read again.
  virtual void unread_rows(std::size_t /*count*/) {}
  // Where field `field` (from 0) of the row read last is.
  virtual SourceLocation field_location(int field) const = 0;
  // Where the last data row is, or the header when there is none.
  virtual SourceLocation last_row_location() const = 0;

  // Parts (ColumnRequest::part). The rows of part `index` of `count` are those whose position
  // lies in [begin, end): a row's index from 0, or for CSV the byte offset of its line.
  struct Bounds {
    std::uint64_t begin = 0, end = 0;
  };
  // Positions the layout `before` rows (fewer at the start of the data) ahead of the first row
  // of the part, and returns the part's bounds. Called once, before the first read_row().
  virtual Bounds seek_part(const ColumnRequest::Part& part) = 0;
  // The position of the row read last.
  virtual std::uint64_t row_position() const = 0;
  // How many lines precede the first one read, for a layout that numbers lines from where
  // seek_part() put it (CSV); 0 for one whose numbers are the file's.
  virtual long long lines_skipped() const { return 0; }

  // For layouts that number their rows, over `rows` rows in all: the part's bounds, and in
  // `first` the row to read first.
  static Bounds row_bounds(std::uint64_t rows, const ColumnRequest::Part& part,
                           std::uint64_t& first);

  // Marks field `field` of the row as missing when the rule passes over missing values; false
  // when it is an error, which the layout reports with missing_value_hint().
  bool pass_over_missing(RowKeys& keys, std::size_t field) const {
    if (request_.layout.missing == MissingValues::kError) return false;
    if (keys.missing_field < 0) keys.missing_field = static_cast<int>(field);
    return true;
  }

  // Takes the value of requested field `field` into the row (or its time or run): NaN is a
  // missing value (pass_over_missing, else an error), any other value must be finite. `bad`
  // reports the value as not what was expected and does not return.
  template <class Bad>
  void take_value(std::size_t field, double value, double* row, RowKeys& keys, Bad&& bad) {
    if (std::isnan(value)) {
      if (!pass_over_missing(keys, field)) {
        bad("expected a number (" + missing_value_hint() + ")");
      }
      return;
    }
    if (!std::isfinite(value)) bad("expected a finite number");
    if (map_.output[field] >= 0) row[map_.output[field]] = value;
    if (static_cast<int>(field) == map_.time) keys.t = value;
    if (static_cast<int>(field) == map_.run && !to_run(value, keys.run)) {
      bad("expected an integer");
    }
  }

  std::string path_;
  ColumnRequest request_;
  bool takes_many_rows_ = false;  // the layout implements read_rows()
  Header header_;
  ColumnMap map_;

 private:
  // The most values a block holds (8 MB): a wide record's blocks have fewer rows.
  static constexpr std::size_t kBlockValues = std::size_t{1} << 20;
  bool next_rows(DataBlock& block, std::size_t max_rows);
  std::size_t take_rows(DataBlock& block, std::size_t max_rows);
  void check_time(double t, bool owned);
  // For owned rows after the first step, none dropped before them: takes the times from the
  // first while each step from the one before is the first step within the allowance. Returns
  // how many it took.
  std::size_t steady_steps(const double* times, std::size_t count);
  // How far a step from `previous` to time t may differ from `reference`, the first step or the
  // metadata's dt.
  double step_allowance(double t, double previous, double reference) const;
  // Its part that does not depend on the times.
  double fixed_allowance(double reference) const;
  [[noreturn]] void non_uniform_step(double t, double step) const;
  RowZone zone_of_last_row() const;

  // Fails when the data have fewer than the requested minimum of rows.
  void finish(std::size_t rows);

  std::optional<double> step_;  // the first step, the reference of the others
  double span_ = 0;             // the steps' sum, over all runs
  std::size_t steps_ = 0;
  double run_span_ = 0;  // the steps' sum and count in the current run, for messages
  std::size_t run_steps_ = 0;
  TimePrecision precision_;  // of the time column
  double previous_time_ = 0;
  bool has_previous_time_ = false;
  bool dropped_ = false;  // a row was dropped since the last one delivered
  bool joined_ = false;   // a dropped row lies between the previous time and the next
  MissingSummary missing_;
  bool started_ = false;
  long current_run_ = 0;
  std::vector<double> pending_;
  bool has_pending_ = false;
  bool pending_run_starts_ = false;
  RowZone pending_zone_ = RowZone::kOwned;
  // A part: its bounds (once positioned), the rows delivered past it, and whether it is done.
  std::optional<Bounds> bounds_;
  std::size_t after_rows_ = 0;
  bool part_done_ = false;
  std::size_t rows_read_ = 0;
  std::vector<double> times_;  // of the rows of read_rows()
};

}  // namespace momentid::data
