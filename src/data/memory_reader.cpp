// Columns in memory read like a file, so that every check of the file readers applies to them.

#include <cmath>

#include "common/decimal.hpp"
#include "data/formats.hpp"
#include "data/stream_reader.hpp"
#include "data/text.hpp"

namespace momentid::data {
namespace {

class MemoryReader final : public StreamReader {
 public:
  MemoryReader(const MemoryData& data, const ColumnRequest& request)
      : StreamReader(data.name, request), data_(data) {
    header_.metadata = data.metadata;
    if (const auto dt = data.metadata.get("dt")) {
      double value = 0;
      if (!is_number(*dt, value) || !std::isfinite(value) || value <= 0) {
        fail({path_, 0, 0, ""}, "metadata dt: expected a positive number, found " +
                                    (dt->empty() ? std::string("nothing") : quoted_field(*dt)));
      }
      header_.metadata_dt = value;
      header_.metadata_dt_source = "dt=" + *dt + " in the metadata";
    }
    for (std::size_t c = 0; c < data.columns.size(); ++c) {
      header_.names.push_back(data.columns[c].name);
      header_.name_columns.push_back(c + 1);
    }
    map_ = map_columns(path_, header_, request_);
    for (std::size_t field = 0; field < header_.names.size(); ++field) {
      if (map_.needed[field]) needed_fields_.push_back(field);
    }
  }

 protected:
  bool read_row(double* row, RowKeys& keys) override {
    if (row_ == data_.rows) return false;
    for (const std::size_t field : needed_fields_) {
      const MemoryColumn& column = data_.columns[field];
      const double value = column.values[row_ * column.stride];
      take_value(field, value, row, keys,
                 [&](const std::string& expected) { bad_value(field, value, expected); });
    }
    ++row_;
    return true;
  }

  std::optional<double> fraction_read() const override {
    if (data_.rows == 0) return std::nullopt;
    return static_cast<double>(row_) / static_cast<double>(data_.rows);
  }

  Bounds seek_part(const ColumnRequest::Part& part) override {
    std::uint64_t first = 0;
    const Bounds bounds = row_bounds(data_.rows, part, first);
    row_ = static_cast<std::size_t>(first);
    return bounds;
  }

  std::uint64_t row_position() const override { return row_ - 1; }

  SourceLocation field_location(int field) const override {
    return {path_, clamp_to_int(static_cast<long long>(row_)), field + 1, ""};
  }

  SourceLocation last_row_location() const override {
    return {path_, clamp_to_int(static_cast<long long>(row_)), 1, ""};
  }

 private:
  [[noreturn]] void bad_value(std::size_t field, double value, const std::string& expected) {
    // The row is counted once it is read whole: this one is the next.
    fail({path_, clamp_to_int(static_cast<long long>(row_ + 1)), static_cast<int>(field) + 1, ""},
         "column '" + header_.names[field] + "': " + expected + ", found '" +
             shortest_decimal(value) + "'");
  }

  const MemoryData& data_;
  std::vector<std::size_t> needed_fields_;
  std::size_t row_ = 0;
};

}  // namespace

std::unique_ptr<DataReader> open_memory(const MemoryData& data, const ColumnRequest& request) {
  return std::make_unique<MemoryReader>(data, request);
}

}  // namespace momentid::data
