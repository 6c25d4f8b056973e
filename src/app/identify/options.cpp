#include <algorithm>
#include <cmath>
#include <string>

#include "momentid/error.hpp"
#include "momentid/identify.hpp"

namespace momentid {

void IdentifyOptions::validate(const Model& model) const {
  if (batches && (*batches < kMinBatches || *batches > kMaxBatches)) {
    throw UsageError("batches", "expected a number from " + std::to_string(kMinBatches) + " to " +
                                    std::to_string(kMaxBatches) + ", found " +
                                    std::to_string(*batches));
  }
  if (degree < 0 || degree > kMaxDegree) {
    throw UsageError("degree", "expected 0 (automatic) or a number from 1 to " +
                                   std::to_string(kMaxDegree) + ", found " +
                                   std::to_string(degree));
  }
  if (input_shift < -kMaxInputShift || input_shift > kMaxInputShift) {
    throw UsageError("input_shift", "expected a number from -" + std::to_string(kMaxInputShift) +
                                        " to " + std::to_string(kMaxInputShift) + ", found " +
                                        std::to_string(input_shift));
  }
  if (method == Method::kZeroLag && (lags || instruments)) {
    throw UsageError("method", "the zero-lag equations take no lags or instruments");
  }
  const auto& variables = model.variables();
  for (const auto& [name, value] : fixed) {
    if (model.parameter_index(name) < 0) {
      throw UsageError("fixed", "'" + name + "' is not a parameter of model " + model.name());
    }
    if (!std::isfinite(value)) {
      throw UsageError("fixed", "the value of '" + name + "' must be a finite number");
    }
  }
  const auto declared_fixed = [&](const Declaration& p) { return p.fixed || fixed.count(p.name); };
  if (!model.parameters().empty() &&
      std::all_of(model.parameters().begin(), model.parameters().end(), declared_fixed)) {
    throw UsageError("fixed", "every parameter of model " + model.name() + " is fixed (by " +
                                  UsageError::mention("fixed") +
                                  " or in the model file): there is nothing to estimate");
  }
  for (const std::string& name : center) {
    if (std::find(variables.begin(), variables.end(), name) == variables.end()) {
      throw UsageError("center", "'" + name + "' is not a state or input of model " + model.name());
    }
  }
  record.validate(&model);
}

const std::vector<ParameterEstimate>& IdentifyResult::parameters() const {
  return estimate.main().parameters;
}

}  // namespace momentid
