#include "momentid/identify.hpp"

#include <memory>
#include <optional>
#include <utility>

#include "app/identify/integrate.hpp"
#include "app/identify/lagged.hpp"
#include "app/identify/latent.hpp"
#include "app/identify/law_check.hpp"
#include "app/identify/plan.hpp"
#include "app/identify/response_means.hpp"
#include "app/identify/zero_lag.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/error.hpp"
#include "momentid/refine.hpp"

namespace momentid {

namespace {

// Identifies with the record surveyed and the states to form planned (none: nullopt).
IdentifyResult identify_with(const Model& model, const DataSource& source,
                             const IdentifyOptions& options, const RecordSurvey& record,
                             std::optional<IdentifyResult::Integration> integration) {
  IdentifyResult result;
  result.model = std::make_shared<const Model>(model);
  result.data_name = source.name();
  result.integration = std::move(integration);
  const EquationChoice choice = choose_equations(model, record, options);
  result.why = choice.why;
  switch (choice.kind) {
    case EquationKind::kZeroLag:
      identify_zero_lag(result, source, options);
      break;
    case EquationKind::kLagged:
      if (!latent_model(model, record.present)) {
        identify_lagged(result, source, options, record.present);
      } else {
        identify_latent(result, source, options, record.present);
      }
      break;
  }
  result.runaway = runaway(result);
  return result;
}

// identify() without the law check.
IdentifyResult identify_unchecked(const Model& model, const DataSource& source,
                                  const IdentifyOptions& options) {
  options.validate(model);
  RecordSurvey record = survey_record(model, source, options.record);
  if (!options.integrate.empty()) {
    IdentifyResult::Integration integration =
        plan_integration(model, source, options, record.present);
    return identify_with(model, source, options, record, std::move(integration));
  }
  try {
    IdentifyResult result = identify_with(model, source, options, record, std::nullopt);
    if (options.integrate_corner) {
      result.estimate.warnings.push_back(
          "--integrate-corner has no effect: no state was formed from a derivative's column (the "
          "equations need none that the record lacks; --integrate names states to form)");
    }
    return result;
  } catch (const FormStatesError& e) {
    // The record shows states only through their derivatives' columns and the equations need
    // the states themselves: the defaults form them, as `integrate` with the states the error
    // names does. Where the user chose the instruments, or the record cannot be filtered (too
    // short, no sample interval), the error stands: it names the option.
    if (options.instruments) throw;
    IdentifyOptions formed = options;
    formed.integrate = e.states();
    IdentifyResult::Integration integration;
    try {
      integration = plan_integration(model, source, formed, record.present);
    } catch (const Interrupted&) {
      throw;
    } catch (const Error&) {
      throw e;
    }
    integration.by_default = true;
    return identify_with(model, source, formed, record, std::move(integration));
  }
}

}  // namespace

IdentifyResult identify(const Model& model, const DataSource& source,
                        const IdentifyOptions& options) {
  const AlgebraLock lock;
  IdentifyResult result = identify_unchecked(model, source, options);
  check_laws(result, options,
             [&](const Model& extended) { return identify_unchecked(extended, source, options); });
  simulate_response_means(result, source, options);
  if (options.refine && result.estimate.usable()) {
    RefineOptions refine_options;
    refine_options.replay.record = options.record;
    refine_options.center = options.center;
    refine_options.start = result.parameters();
    // A refinement that cannot run (the identified model blows up in the simulation) leaves the
    // moment estimate standing, with a doubt that says why.
    try {
      RefineResult refined = refine(*result.model, source, refine_options);
      refined.start_from = "the moment estimate";
      result.refinement = std::make_shared<const RefineResult>(std::move(refined));
    } catch (const Interrupted&) {
      throw;
    } catch (const Error& e) {
      result.refinement_failure = e.what();
    }
  }
  return result;
}

}  // namespace momentid
