#include "momentid/check.hpp"

#include <algorithm>
#include <optional>

#include "app/variables.hpp"
#include "data/header.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/derive.hpp"
#include "momentid/lagged.hpp"

namespace momentid {

void CheckOptions::validate(const Model* model) const {
  if (lags < 1 || lags > kMaxLags) {
    throw UsageError("lags", "expected a number from 1 to " + std::to_string(kMaxLags) +
                                 ", found " + std::to_string(lags));
  }
  record.validate(model);
}

CheckResult check(const DataSource& source, const Model* model, const CheckOptions& options) {
  const AlgebraLock lock;
  options.validate(model);
  CheckResult result;
  result.data_name = source.name();
  result.lags = options.lags;
  result.with_model = model != nullptr;
  std::vector<std::string> states, inputs, derivatives;
  // Per model variable: whether the check reads it.
  std::vector<bool> kept;
  if (model != nullptr) {
    const std::vector<bool> present = variables_present(*model, source, options.record);
    // The statistics of the states and most identities need no input: inputs missing from the
    // data are left out rather than refused (all of them, so that the channels are the states).
    // So are states the data show only as derivatives (v when y' = v and y is measured); any
    // other missing state is requested, and reported as a missing column.
    const bool derivable = derivable_from(*model, present);
    const auto is_state = [&](std::size_t v) {
      return model->variables()[v].kind == VariableKind::kState;
    };
    // A column that measures a derivative is read when the record has it.
    const auto is_derivative = [&](std::size_t v) {
      return model->variables()[v].kind == VariableKind::kDerivative;
    };
    for (std::size_t v = 0; v < present.size(); ++v) {
      const std::string& name = model->variables()[v].name;
      if (is_derivative(v)) {
        kept.push_back(present[v]);
      } else if (is_state(v) && !present[v] && derivable) {
        result.missing_states.push_back(name);
        kept.push_back(false);
      } else if (!is_state(v) && !present[v]) {
        result.missing_inputs.push_back(name);
        kept.push_back(false);
      } else {
        kept.push_back(true);
      }
    }
    for (std::size_t v = 0; v < kept.size(); ++v) {
      if (is_derivative(v)) {
        if (kept[v]) derivatives.push_back(model->variables()[v].name);
        continue;
      }
      if (!is_state(v) && !result.missing_inputs.empty()) kept[v] = false;
      if (kept[v]) (is_state(v) ? states : inputs).push_back(model->variables()[v].name);
    }
  } else {
    const std::unique_ptr<DataReader> reader = source.open({.names = {},
                                                            .rename = options.record.columns,
                                                            .min_rows = 0,
                                                            .layout = options.record.layout});
    const std::vector<std::string> columns = reader->columns();
    for (const auto& [name, why] : reader->unusable_columns()) {
      result.warnings.push_back("not checked: " + why);
    }
    const auto time = options.record.columns.find("t");
    for (const std::string& c : columns) {
      const bool is_time = time != options.record.columns.end() ? c == time->second
                                                                : c == "t" || data::is_time_name(c);
      if (!c.empty() && !is_time && c != "run") states.push_back(c);
    }
  }
  std::optional<MomentSystem> system;
  std::vector<Monomial> moments;
  std::vector<Monomial> full_moments;  // over all the model's variables
  if (model != nullptr) {
    system = derive(*model);
    // The identities hold polynomial moments only: a moment with abs(...) or sign(...) (a
    // variable after the channels) is left out.
    for (const Monomial& m : moments_to_estimate(*system)) {
      std::vector<int> over_kept;
      bool readable = true;
      for (std::size_t v = 0; v < m.size(); ++v) {
        if (v < kept.size() && kept[v]) {
          over_kept.push_back(m[v]);
        } else if (m[v] != 0) {
          readable = false;
        }
      }
      if (!readable) continue;
      full_moments.push_back(m);
      moments.emplace_back(std::move(over_kept));
    }
  }
  DataOptions data_options;
  data_options.lags = options.lags;
  data_options.record = options.record;
  data_options.derivatives = derivatives;
  result.data = moments_from_data(source, states, inputs, moments, data_options);
  if (system) result.identities = check_identities(*system, full_moments, result.data.estimates);
  for (std::string& w : data_warnings(result.data)) result.warnings.push_back(std::move(w));
  return result;
}

}  // namespace momentid
