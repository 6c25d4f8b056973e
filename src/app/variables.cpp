#include "app/variables.hpp"

#include <algorithm>

namespace momentid {

std::vector<std::string> data_columns(const DataSource& source, const RecordOptions& record) {
  return source
      .open({.names = {}, .rename = record.columns, .min_rows = 0, .layout = record.layout})
      ->columns();
}

std::vector<bool> variables_present(const Model& model, const DataSource& source,
                                    const RecordOptions& record) {
  // An array the file has under a variable's name but cannot give as a column counts as
  // present: reading it then says why it is unusable, rather than the variable passing for
  // unmeasured.
  const std::unique_ptr<DataReader> reader =
      source.open({.names = {}, .rename = record.columns, .min_rows = 0, .layout = record.layout});
  std::vector<std::string> header = reader->columns();
  for (const auto& [name, why] : reader->unusable_columns()) header.push_back(name);
  std::vector<bool> present;
  for (const std::string& v : model.variables()) {
    const auto renamed = record.columns.find(v);
    const std::string& column = renamed == record.columns.end() ? v : renamed->second;
    present.push_back(std::find(header.begin(), header.end(), column) != header.end());
  }
  return present;
}

}  // namespace momentid
