#include "app/variables.hpp"

#include <algorithm>

namespace momentid {

std::vector<bool> variables_present(const Model& model, const DataSource& source,
                                    const std::map<std::string, std::string>& columns) {
  const std::vector<std::string> header =
      source.open({.names = {}, .rename = {}, .min_rows = 0})->columns();
  std::vector<bool> present;
  for (const std::string& v : model.variables()) {
    const auto renamed = columns.find(v);
    const std::string& column = renamed == columns.end() ? v : renamed->second;
    present.push_back(std::find(header.begin(), header.end(), column) != header.end());
  }
  return present;
}

}  // namespace momentid
