#include "app/variables.hpp"

#include <algorithm>
#include <span>

namespace momentid {

std::vector<std::string> data_columns(const DataSource& source, const RecordOptions& record) {
  return source
      .open({.names = {}, .rename = record.columns, .min_rows = 0, .layout = record.layout})
      ->columns();
}

namespace {

std::unique_ptr<DataReader> open_header(const DataSource& source, const RecordOptions& record) {
  return source.open(
      {.names = {}, .rename = record.columns, .min_rows = 0, .layout = record.layout});
}

// An array the file has under a variable's name but cannot give as a column counts as present:
// reading it then says why it is unusable, rather than the variable passing for unmeasured.
std::vector<bool> present_in(const Model& model, const DataReader& reader,
                             const RecordOptions& record, const std::string& source_name) {
  std::vector<std::string> header = reader.columns();
  for (const auto& [name, why] : reader.unusable_columns()) header.push_back(name);
  std::vector<bool> present;
  for (const Variable& v : model.variables()) {
    if (!v.channel()) continue;
    const auto renamed = record.columns.find(v.name);
    const std::string& column = renamed == record.columns.end() ? v.name : renamed->second;
    const auto has = [&](const std::string& c) {
      return std::find(header.begin(), header.end(), c) != header.end();
    };
    // A sum of columns is present when every column it reads is (column_sum says which not).
    present.push_back(has(column) || column_sum(v.name, column, header, source_name).has_value());
  }
  return present;
}

}  // namespace

std::vector<bool> variables_present(const Model& model, const DataSource& source,
                                    const RecordOptions& record) {
  return present_in(model, *open_header(source, record), record, source.name());
}

RecordSurvey survey_record(const Model& model, const DataSource& source,
                           const RecordOptions& record) {
  const std::unique_ptr<DataReader> reader = open_header(source, record);
  RecordSurvey out;
  out.present = present_in(model, *reader, record, source.name());
  const DataMetadata& metadata = reader->metadata();
  // simulate writes the model's name, and noise.NAME or noise-sd.NAME for the noise it adds.
  out.noise_free = metadata.get("model").has_value();
  out.described = !metadata.lines().empty();
  for (const auto& line : metadata.lines()) {
    for (const auto& [key, value] : line) {
      if (key.starts_with("noise")) out.noise_free = false;
    }
  }
  const auto time = record.columns.find("t");
  const std::string time_column = time == record.columns.end() ? "t" : time->second;
  const auto& columns = reader->columns();
  out.timed = record.dt || reader->time_step() ||
              std::find(columns.begin(), columns.end(), time_column) != columns.end();
  return out;
}

}  // namespace momentid
