#include "momentid/record_options.hpp"

#include <algorithm>
#include <cmath>
#include <span>

#include "momentid/error.hpp"
#include "momentid/model.hpp"

namespace momentid {

void RecordOptions::validate(const Model* model) const {
  if (dt && !(std::isfinite(*dt) && *dt > 0)) {
    throw UsageError("dt", "expected a positive number");
  }
  if (model == nullptr) return;
  const std::vector<std::string> variables = model->channel_names();
  for (const auto& column : columns) {
    if (column.first == "t") continue;
    if (std::find(variables.begin(), variables.end(), column.first) == variables.end()) {
      throw UsageError("columns",
                       "'" + column.first + "' is not a state or input of model " + model->name());
    }
  }
}

}  // namespace momentid
