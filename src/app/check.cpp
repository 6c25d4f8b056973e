#include "momentid/check.hpp"

#include <algorithm>
#include <memory>
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

namespace {

// The channels check reads, as the pass takes them; per model variable, whether it is read.
struct CheckedChannels {
  std::vector<std::string> states, inputs, derivatives;
  std::vector<bool> kept;
};

// A model's channels that the record has. The statistics of the states and most identities need
// no input: inputs missing from the data are left out rather than refused (all of them, so that
// the channels are the states). So are states the data show only as derivatives (v when y' = v
// and y is measured); any other missing state is requested, and reported as a missing column.
// A column that measures a derivative is read when the record has it.
CheckedChannels model_channels(const Model& model, const DataSource& source,
                               const CheckOptions& options, CheckResult& result) {
  CheckedChannels out;
  const std::vector<bool> present = variables_present(model, source, options.record);
  const bool derivable = derivable_from(model, present);
  const auto kind = [&](std::size_t v) { return model.variables()[v].kind; };
  for (std::size_t v = 0; v < present.size(); ++v) {
    const std::string& name = model.variables()[v].name;
    if (kind(v) == VariableKind::kDerivative) {
      out.kept.push_back(present[v]);
    } else if (kind(v) == VariableKind::kState && !present[v] && derivable) {
      result.missing_states.push_back(name);
      out.kept.push_back(false);
    } else if (kind(v) != VariableKind::kState && !present[v]) {
      result.missing_inputs.push_back(name);
      out.kept.push_back(false);
    } else {
      out.kept.push_back(true);
    }
  }
  for (std::size_t v = 0; v < out.kept.size(); ++v) {
    const std::string& name = model.variables()[v].name;
    if (kind(v) == VariableKind::kDerivative) {
      if (out.kept[v]) out.derivatives.push_back(name);
      continue;
    }
    const bool state = kind(v) == VariableKind::kState;
    if (!state && !result.missing_inputs.empty()) out.kept[v] = false;
    if (out.kept[v]) (state ? out.states : out.inputs).push_back(name);
  }
  return out;
}

// Without a model: every column of the record but the time and the run, each as a state.
CheckedChannels file_channels(const DataSource& source, const CheckOptions& options,
                              CheckResult& result) {
  CheckedChannels out;
  const std::unique_ptr<DataReader> reader = source.open({.names = {},
                                                          .rename = options.record.columns,
                                                          .min_rows = 0,
                                                          .layout = options.record.layout});
  for (const auto& [name, why] : reader->unusable_columns()) {
    result.warnings.push_back("not checked: " + why);
  }
  const auto time = options.record.columns.find("t");
  for (const std::string& c : reader->columns()) {
    const bool is_time = time != options.record.columns.end() ? c == time->second
                                                              : c == "t" || data::is_time_name(c);
    if (!c.empty() && !is_time && c != "run") out.states.push_back(c);
  }
  return out;
}

}  // namespace

CheckResult check(const DataSource& source, const Model* model, const CheckOptions& options) {
  const AlgebraLock lock;
  options.validate(model);
  CheckResult result;
  result.data_name = source.name();
  result.lags = options.lags;
  result.with_model = model != nullptr;
  const CheckedChannels channels = model != nullptr
                                       ? model_channels(*model, source, options, result)
                                       : file_channels(source, options, result);
  const std::vector<bool>& kept = channels.kept;
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
  data_options.derivatives = channels.derivatives;
  result.data = moments_from_data(source, channels.states, channels.inputs, moments, data_options);
  if (system) result.identities = check_identities(*system, full_moments, result.data.estimates);
  if (std::optional<std::string> w = outlier_warning(result.data)) result.warnings.push_back(*w);
  for (std::string& w : data_warnings(result.data)) result.warnings.push_back(std::move(w));
  return result;
}

}  // namespace momentid
