// Several files as one record of many runs (DataSource::files).

#include <cmath>

#include "common/decimal.hpp"
#include "data/formats.hpp"
#include "data/text.hpp"

namespace momentid::data {
namespace {

class ChainReader final : public DataReader {
 public:
  ChainReader(const std::vector<std::string>& paths, const ColumnRequest& request)
      : paths_(paths), request_(request), min_rows_(request.min_rows) {
    // The minimum is the whole record's, checked at its end, not each file's.
    request_.min_rows = 0;
    if (paths_.empty()) throw UsageError("no data files");
    open_next();
  }

  const DataMetadata& metadata() const override { return first_metadata_; }
  const std::vector<std::string>& columns() const override { return first_columns_; }
  std::map<std::string, std::string> unusable_columns() const override {
    return current_->unusable_columns();
  }

  std::optional<double> time_step() const override {
    // Files read to their end were checked to agree with the first.
    return first_step_ ? first_step_ : current_->time_step();
  }

  bool next(DataBlock& block, std::size_t max_rows) override {
    while (!current_->next(block, max_rows)) {
      finish_file();
      if (file_ + 1 == paths_.size()) {
        if (rows_ < min_rows_) {
          fail({paths_.back(), 1, 1, ""}, "the data have " + plural(rows_, "row") + " in " +
                                              plural(paths_.size(), "file") + "; at least " +
                                              std::to_string(min_rows_) + " are needed");
        }
        return false;
      }
      ++file_;
      open_next();
    }
    // A file's first block begins a run: runs are never joined across files.
    if (fresh_) block.run_starts = true;
    fresh_ = false;
    rows_ += block.rows;
    return true;
  }

  std::size_t rows_read() const override { return rows_; }

  // Each file counts alike.
  std::optional<double> fraction_read() const override {
    const double within = current_->fraction_read().value_or(0);
    return (static_cast<double>(file_) + within) / static_cast<double>(paths_.size());
  }
  const MissingSummary& missing() const override { return missing_; }

 private:
  void open_next() {
    current_ = DataReader::open(paths_[file_], request_);
    fresh_ = true;
    if (file_ == 0) {
      first_metadata_ = current_->metadata();
      first_columns_ = current_->columns();
    }
  }

  // After a file's last row: its interval must be the first file's; its missing values count.
  void finish_file() {
    const std::optional<double> step = current_->time_step();
    if (file_ == 0) {
      first_step_ = step;
    } else {
      check_file_interval(paths_[file_], step, paths_.front(), first_step_);
    }
    missing_.add(current_->missing());
  }

  std::vector<std::string> paths_;
  ColumnRequest request_;
  std::size_t min_rows_;
  std::size_t file_ = 0, rows_ = 0;
  bool fresh_ = false;
  std::unique_ptr<DataReader> current_;
  DataMetadata first_metadata_;
  std::vector<std::string> first_columns_;
  std::optional<double> first_step_;
  MissingSummary missing_;
};

}  // namespace

void check_file_interval(const std::string& file, const std::optional<double>& step,
                         const std::string& first_file, const std::optional<double>& first_step) {
  if (step.has_value() == first_step.has_value() &&
      (!step || std::abs(*step - *first_step) <= 1e-6 * *first_step)) {
    return;
  }
  const auto text = [](const std::optional<double>& s) {
    return s ? "dt = " + shortest_decimal(*s) : std::string("no sample interval");
  };
  fail({file, 1, 1, ""}, "this file has " + text(step) + ", but " + first_file + " has " +
                             text(first_step) +
                             ": the files of one identification need one interval");
}

std::unique_ptr<DataReader> open_chain(const std::vector<std::string>& paths,
                                       const ColumnRequest& request) {
  return std::make_unique<ChainReader>(paths, request);
}

}  // namespace momentid::data
