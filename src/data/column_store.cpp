#include "data/column_store.hpp"

#include <algorithm>
#include <cmath>

#include "common/decimal.hpp"
#include "data/header.hpp"
#include "data/stream_reader.hpp"
#include "data/text.hpp"

namespace momentid::data {
namespace {

// Samples read per channel at a time: memory stays flat whatever the length.
constexpr std::size_t kChunkRows = 1 << 15;

class ColumnStoreReader final : public StreamReader {
 public:
  ColumnStoreReader(std::unique_ptr<ColumnStore> store, const std::string& path,
                    const ColumnRequest& request)
      : StreamReader(path, request), store_(std::move(store)) {
    header_.names = store_->names();
    header_.listing = std::string("the file has the ") + store_->kind() + "s";
    header_.line = 1;
    for (std::size_t c = 0; c < header_.names.size(); ++c) header_.name_columns.push_back(c + 1);
    header_.metadata = store_->metadata();
    if (const auto dt = header_.metadata.get("dt")) {
      double value = 0;
      if (!is_number(*dt, value) || !(value > 0) || !std::isfinite(value)) {
        fail(start(), "metadata dt: expected a positive number, found " + quoted_field(*dt));
      }
      header_.metadata_dt = value;
      header_.metadata_dt_text = *dt;
    }
    if (request_.layout.dt_from && !request_.dt) dt_from_scalar();
    for (auto& [variable, column] : request_.rename) column = store_->column_name(column);
    for (const std::string& name : request_.names) {
      const auto renamed = request_.rename.find(name);
      const std::string& column = renamed == request_.rename.end() ? name : renamed->second;
      if (std::find(header_.names.begin(), header_.names.end(), column) != header_.names.end()) {
        continue;
      }
      if (const auto why = store_->unusable(column)) fail(start(), *why);
    }
    map_ = map_columns(path_, header_, request_);
    for (std::size_t field = 0; field < header_.names.size(); ++field) {
      if (!map_.needed[field]) continue;
      store_->prepare(field);
      const std::size_t length = store_->length(field);
      if (!needed_fields_.empty() && length != rows_) {
        const std::size_t first = needed_fields_.front();
        fail(start(), std::string(store_->kind()) + " '" + header_.names[field] + "' has " +
                          plural(length, "value") + " but '" + header_.names[first] + "' has " +
                          std::to_string(rows_) + ": every channel needs one value per sample");
      }
      rows_ = length;
      needed_fields_.push_back(field);
    }
    chunk_.resize(needed_fields_.size());
  }

 protected:
  bool read_row(double* row, RowKeys& keys) override {
    if (row_ == rows_) return false;
    if (row_ == chunk_end_) load_chunk();
    const std::size_t at = row_ - chunk_start_;
    ++row_;
    for (std::size_t k = 0; k < needed_fields_.size(); ++k) {
      const std::size_t field = needed_fields_[k];
      const double value = chunk_[k][at];
      if (std::isnan(value)) {
        if (!pass_over_missing(keys, field)) {
          bad_value(field, value, std::string("expected a number (") + kMissingHint + ")");
        }
        continue;
      }
      if (!std::isfinite(value)) bad_value(field, value, "expected a finite number");
      if (map_.output[field] >= 0) row[map_.output[field]] = value;
      if (static_cast<int>(field) == map_.time) keys.t = value;
      if (static_cast<int>(field) == map_.run && !to_run(value, keys.run)) {
        bad_value(field, value, "expected an integer");
      }
    }
    return true;
  }

  SourceLocation field_location(int field) const override {
    return {path_, clamp_to_int(static_cast<long long>(row_)), field + 1, ""};
  }

  SourceLocation last_row_location() const override {
    return {path_, clamp_to_int(static_cast<long long>(std::max<std::size_t>(row_, 1))), 1, ""};
  }

 private:
  SourceLocation start() const { return {path_, 1, 1, ""}; }

  void load_chunk() {
    chunk_start_ = row_;
    chunk_end_ = std::min(rows_, row_ + kChunkRows);
    for (std::size_t k = 0; k < needed_fields_.size(); ++k) {
      chunk_[k].resize(chunk_end_ - chunk_start_);
      store_->read(needed_fields_[k], chunk_start_, chunk_end_ - chunk_start_, chunk_[k].data());
    }
  }

  // FileLayout::dt_from: `NAME` holds the interval, `1/NAME` the rate.
  void dt_from_scalar() {
    std::string name = *request_.layout.dt_from;
    const bool rate = name.starts_with("1/");
    if (rate) name = name.substr(2);
    const std::optional<double> value = store_->scalar(name);
    if (!value) {
      fail(start(), "--dt-from: no scalar named '" + name + "' in the file");
    }
    const double dt = rate ? 1 / *value : *value;
    if (!(dt > 0) || !std::isfinite(dt)) {
      fail(start(), "--dt-from: '" + name + "' is " + shortest_decimal(*value) +
                        ", which gives no positive sample interval");
    }
    header_.metadata_dt = dt;
    header_.metadata_dt_text = shortest_decimal(dt);
  }

  [[noreturn]] void bad_value(std::size_t field, double value, const std::string& expected) {
    fail(field_location(static_cast<int>(field)), "'" + header_.names[field] + "': " + expected +
                                                      ", found '" + shortest_decimal(value) + "'");
  }

  std::unique_ptr<ColumnStore> store_;
  std::vector<std::size_t> needed_fields_;
  std::size_t rows_ = 0, row_ = 0, chunk_start_ = 0, chunk_end_ = 0;
  std::vector<std::vector<double>> chunk_;  // per needed field
};

}  // namespace

std::unique_ptr<DataReader> open_column_store(std::unique_ptr<ColumnStore> store,
                                              const std::string& path,
                                              const ColumnRequest& request) {
  return std::make_unique<ColumnStoreReader>(std::move(store), path, request);
}

}  // namespace momentid::data
