#pragma once

#include <map>
#include <string>
#include <vector>

#include "momentid/model.hpp"
#include "momentid/reader.hpp"

namespace momentid {

// Per model variable (states, then inputs): whether `source` has its column, under the name
// `columns` maps it to (model name -> data column) or its own. Reads the header only.
std::vector<bool> variables_present(const Model& model, const DataSource& source,
                                    const std::map<std::string, std::string>& columns);

}  // namespace momentid
