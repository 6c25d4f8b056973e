#include "momentid/identify.hpp"

#include <memory>

#include "app/identify/steps.hpp"
#include "app/variables.hpp"

namespace momentid {

IdentifyResult identify(const Model& model, const DataSource& source,
                        const IdentifyOptions& options) {
  options.validate(model);
  IdentifyResult result;
  result.model = std::make_shared<const Model>(model);
  result.data_name = source.name();
  // Which variables the data have: the lagged equations serve data without some state.
  const std::vector<bool> measured = variables_present(model, source, options.record);
  switch (choose_equations(model, measured, options)) {
    case EquationKind::kZeroLag:
      identify_zero_lag(result, source, options);
      break;
    case EquationKind::kLagged:
      identify_lagged(result, source, options, measured);
      break;
  }
  return result;
}

}  // namespace momentid
