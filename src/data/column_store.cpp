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
    const std::vector<std::string> all = store_->names();
    std::vector<std::string> prefixes = request_.layout.runs;
    if (prefixes.empty()) prefixes.push_back("");
    // The names a user sees are those of the first run, without its prefix.
    for (const std::string& name : all) {
      if (name.starts_with(prefixes.front())) {
        header_.names.push_back(name.substr(prefixes.front().size()));
      }
    }
    for (const auto& [name, why] : store_->unusable_names()) {
      if (name.starts_with(prefixes.front())) {
        unusable_[name.substr(prefixes.front().size())] = why;
      }
    }
    header_.listing = std::string("the file has the ") + store_->kind() + "s";
    header_.item = store_->kind();
    header_.line = 1;
    for (std::size_t c = 0; c < header_.names.size(); ++c) header_.name_columns.push_back(c + 1);
    header_.metadata = store_->metadata();
    if (const auto dt = header_.metadata.get("dt")) {
      double value = 0;
      if (!is_number(*dt, value) || !(value > 0) || !std::isfinite(value)) {
        fail(start(), "metadata dt: expected a positive number, found " + quoted_field(*dt));
      }
      header_.metadata_dt = value;
      header_.metadata_dt_source = "dt=" + *dt + " in the metadata";
    }
    if (request_.layout.dt_from && !request_.dt) dt_from_scalar();
    for (auto& [variable, column] : request_.rename) column = store_->column_name(column);
    names_ = all;
    Header every = header_;
    every.names = all;
    every.name_columns.clear();
    for (std::size_t c = 0; c < all.size(); ++c) every.name_columns.push_back(c + 1);
    for (const std::string& prefix : prefixes) plan_run(every, prefix);
    map_ = runs_.front().map;
    if (!request_.layout.dt_from && !request_.dt) use_stated_intervals();
    chunk_.resize(runs_.front().fields.size());
  }

 protected:
  bool read_row(double* row, RowKeys& keys) override {
    while (row_ == runs_[run_].rows) {
      if (run_ + 1 == runs_.size()) return false;
      ++run_;
      row_ = chunk_start_ = chunk_end_ = 0;
      map_ = runs_[run_].map;
      chunk_.resize(runs_[run_].fields.size());
    }
    const RunPlan& plan = runs_[run_];
    if (row_ == chunk_end_) load_chunk();
    const std::size_t at = row_ - chunk_start_;
    ++row_;
    if (runs_.size() > 1) keys.run = static_cast<long>(run_) + 1;
    for (std::size_t k = 0; k < plan.fields.size(); ++k) {
      const std::size_t field = plan.fields[k];
      const double value = chunk_[k][at];
      take_value(field, value, row, keys,
                 [&](const std::string& expected) { bad_value(field, value, expected); });
    }
    return true;
  }

  std::optional<double> fraction_read() const override {
    std::size_t total = 0, done = row_;
    for (std::size_t r = 0; r < runs_.size(); ++r) {
      total += runs_[r].rows;
      if (r < run_) done += runs_[r].rows;
    }
    if (total == 0) return std::nullopt;
    return static_cast<double>(done) / static_cast<double>(total);
  }

  // A row's position counts the rows of the runs before it.
  Bounds seek_part(const ColumnRequest::Part& part) override {
    std::uint64_t total = 0, first = 0;
    for (const RunPlan& plan : runs_) total += plan.rows;
    const Bounds bounds = row_bounds(total, part, first);
    run_ = 0;
    while (run_ + 1 < runs_.size() && first >= runs_[run_].rows) first -= runs_[run_++].rows;
    row_ = chunk_start_ = chunk_end_ = static_cast<std::size_t>(first);
    map_ = runs_[run_].map;
    chunk_.resize(runs_[run_].fields.size());
    return bounds;
  }

  std::uint64_t row_position() const override {
    std::uint64_t position = row_ - 1;
    for (std::size_t r = 0; r < run_; ++r) position += runs_[r].rows;
    return position;
  }

  SourceLocation field_location(int field) const override {
    return {path_, clamp_to_int(static_cast<long long>(row_)), field + 1, ""};
  }

  SourceLocation last_row_location() const override {
    return {path_, clamp_to_int(static_cast<long long>(std::max<std::size_t>(row_, 1))), 1, ""};
  }

  std::map<std::string, std::string> unusable_columns() const override { return unusable_; }

 private:
  // The channels, their map and their length in one run.
  struct RunPlan {
    std::string prefix;
    ColumnMap map;
    std::vector<std::size_t> fields;  // needed channels, in file order
    std::size_t rows = 0;
  };

  SourceLocation start() const { return {path_, 1, 1, ""}; }

  // The fields of run `prefix` (FileLayout::runs): every requested name, and `t`, read from
  // the channel of that name with the prefix in front.
  void plan_run(const Header& every, const std::string& prefix) {
    ColumnRequest request = request_;
    const auto present = [&](const std::string& name) {
      return std::find(every.names.begin(), every.names.end(), name) != every.names.end();
    };
    for (const std::string& name : request_.names) {
      const auto renamed = request_.rename.find(name);
      const std::string column =
          prefix + (renamed == request_.rename.end() ? name : renamed->second);
      request.rename[name] = column;
      if (!present(column)) {
        if (const auto why = store_->unusable(column)) fail(start(), *why);
      }
    }
    if (!prefix.empty()) {
      const auto time = request_.rename.find("t");
      const std::string column = prefix + (time == request_.rename.end() ? "t" : time->second);
      if (present(column) || time != request_.rename.end()) request.rename["t"] = column;
    }
    RunPlan plan{prefix, map_columns(path_, every, request), {}, 0};
    for (std::size_t field = 0; field < every.names.size(); ++field) {
      if (!plan.map.needed[field]) continue;
      store_->prepare(field);
      const std::size_t length = store_->length(field);
      if (!plan.fields.empty() && length != plan.rows) {
        const std::string& first = every.names[plan.fields.front()];
        fail(start(), std::string(store_->kind()) + " '" + every.names[field] + "' has " +
                          plural(length, "value") + " but '" + first + "' has " +
                          std::to_string(plan.rows) + ": every channel needs one value per sample");
      }
      plan.rows = length;
      plan.fields.push_back(field);
    }
    runs_.push_back(std::move(plan));
  }

  void load_chunk() {
    const RunPlan& plan = runs_[run_];
    chunk_start_ = row_;
    chunk_end_ = std::min(plan.rows, row_ + kChunkRows);
    for (std::size_t k = 0; k < plan.fields.size(); ++k) {
      chunk_[k].resize(chunk_end_ - chunk_start_);
      store_->read(plan.fields[k], chunk_start_, chunk_end_ - chunk_start_, chunk_[k].data());
    }
  }

  // FileLayout::dt_from: `NAME` holds the interval, `1/NAME` the rate.
  void dt_from_scalar() {
    std::string name = *request_.layout.dt_from;
    const bool rate = name.starts_with("1/");
    if (rate) name = name.substr(2);
    const std::optional<double> value = store_->scalar(name);
    if (!value) {
      fail(start(),
           UsageError::mention("dt_from") + ": no scalar named '" + name + "' in the file");
    }
    const double dt = rate ? 1 / *value : *value;
    if (!(dt > 0) || !std::isfinite(dt)) {
      fail(start(), UsageError::mention("dt_from") + ": '" + name + "' is " +
                        shortest_decimal(*value) + ", which gives no positive sample interval");
    }
    header_.metadata_dt = dt;
    header_.metadata_dt_source = UsageError::mention("dt_from") + " " + *request_.layout.dt_from +
                                 " = " + shortest_decimal(dt);
  }

  // The metadata's dt and the intervals the file states: they must agree, and one that cannot
  // be used is an error when nothing else gives the interval.
  void use_stated_intervals() {
    std::vector<std::size_t> channels;
    for (const RunPlan& plan : runs_)
      channels.insert(channels.end(), plan.fields.begin(), plan.fields.end());
    struct Usable {
      double dt;
      std::string source;
    };
    std::vector<Usable> usable;
    if (header_.metadata_dt) usable.push_back({*header_.metadata_dt, header_.metadata_dt_source});
    std::optional<StatedInterval> unusable;
    for (StatedInterval& stated : store_->stated_intervals(channels)) {
      const double dt = !stated.value          ? 0
                        : is_rate(stated.name) ? 1 / *stated.value
                                               : *stated.value;
      if (stated.value && !(dt > 0 && std::isfinite(dt))) {
        stated.why = "is " + shortest_decimal(*stated.value) + ", not a positive number";
      } else if (stated.value) {
        usable.push_back({dt, stated.where + " = " + shortest_decimal(*stated.value)});
        continue;
      }
      if (!unusable) unusable = std::move(stated);
    }
    for (const Usable& other : usable) {
      if (std::abs(other.dt - usable.front().dt) > 1e-6 * usable.front().dt) {
        fail(start(), other.source + " disagrees with " + usable.front().source +
                          " (sample intervals " + shortest_decimal(other.dt) + " and " +
                          shortest_decimal(usable.front().dt) + ")");
      }
    }
    if (!usable.empty()) {
      header_.metadata_dt = usable.front().dt;
      header_.metadata_dt_source = usable.front().source;
    } else if (unusable && map_.time < 0) {
      fail(start(), unusable->where + " " + unusable->why +
                        ", and the file has no time channel: give the sample interval with " +
                        UsageError::mention("dt"));
    }
  }

  [[noreturn]] void bad_value(std::size_t field, double value, const std::string& expected) {
    fail(field_location(static_cast<int>(field)), std::string(store_->kind()) + " '" +
                                                      names_[field] + "': " + expected +
                                                      ", found '" + shortest_decimal(value) + "'");
  }

  std::unique_ptr<ColumnStore> store_;
  std::map<std::string, std::string> unusable_;  // store_->unusable_names() of the first run
  std::vector<std::string> names_;               // every channel of the store
  std::vector<RunPlan> runs_;
  std::size_t run_ = 0, row_ = 0, chunk_start_ = 0, chunk_end_ = 0;
  std::vector<std::vector<double>> chunk_;  // per needed field of the current run
};

}  // namespace

std::unique_ptr<DataReader> open_column_store(std::unique_ptr<ColumnStore> store,
                                              const std::string& path,
                                              const ColumnRequest& request) {
  return std::make_unique<ColumnStoreReader>(std::move(store), path, request);
}

}  // namespace momentid::data
