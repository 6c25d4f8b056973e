#include "momentid/identify.hpp"

#include <memory>

#include "app/identify/integrate.hpp"
#include "app/identify/lagged.hpp"
#include "app/identify/plan.hpp"
#include "app/identify/zero_lag.hpp"
#include "momentid/algebra_lock.hpp"

namespace momentid {

IdentifyResult identify(const Model& model, const DataSource& source,
                        const IdentifyOptions& options) {
  const AlgebraLock lock;
  options.validate(model);
  IdentifyResult result;
  result.model = std::make_shared<const Model>(model);
  result.data_name = source.name();
  RecordSurvey record = survey_record(model, source, options.record);
  if (!options.integrate.empty()) {
    result.integration = plan_integration(model, source, options, record.present);
  }
  const EquationChoice choice = choose_equations(model, record, options);
  result.why = choice.why;
  switch (choice.kind) {
    case EquationKind::kZeroLag:
      identify_zero_lag(result, source, options);
      break;
    case EquationKind::kLagged:
      identify_lagged(result, source, options, record.present);
      break;
  }
  result.runaway = runaway(result);
  return result;
}

}  // namespace momentid
