// The choices identify() makes before it reads the record.

#include "app/identify/plan.hpp"

#include <algorithm>

#include "momentid/lagged.hpp"

namespace momentid {
namespace {

// Whether data with the channels flagged in `measured` show every state and input, measured or
// as a derivative: then the lagged equations take them, and name any abs or sign term whose
// argument they lack.
bool channels_derivable(const Model& model, const std::vector<bool>& measured) {
  const std::vector<VariableReading> readings = variable_readings(model, measured);
  return std::all_of(readings.begin(), readings.begin() + static_cast<long>(model.channel_count()),
                     [](const VariableReading& r) { return r.base >= 0; });
}

}  // namespace

bool latent_model(const Model& model, const std::vector<bool>& measured) {
  const std::vector<VariableReading> readings = variable_readings(model, measured);
  const std::size_t states = model.states().size(), inputs = model.inputs().size();
  const auto shown = [](const VariableReading& r) { return r.base >= 0; };
  const auto end = readings.begin() + static_cast<long>(states);
  return std::any_of(readings.begin(), end, shown) && !std::all_of(readings.begin(), end, shown) &&
         std::all_of(measured.begin() + static_cast<long>(states),
                     measured.begin() + static_cast<long>(states + inputs),
                     [](bool m) { return m; });
}

EquationChoice choose_equations(const Model& model, const RecordSurvey& record,
                                const IdentifyOptions& options) {
  using enum EquationKind;
  const std::vector<bool>& measured = record.present;
  if (options.method == Method::kZeroLag) return {kZeroLag, "asked for"};
  if (latent_model(model, measured)) {
    return {kLagged,
            "the record shows some states in no way: the equations with these latent "
            "states eliminated are lagged ones (docs/latent-states.md)"};
  }
  if (options.method == Method::kLagged) return {kLagged, "asked for"};
  if (options.lags || options.instruments) return {kLagged, "lags or instruments were given"};
  if (!options.integrate.empty())
    return {kLagged, "they read the states formed from a derivative's column"};
  const bool all_measured = std::all_of(measured.begin(), measured.end(), [](bool m) { return m; });
  if (!all_measured) {
    // Data that cannot show a state, not even as a derivative, get the zero-lag pass and its
    // message naming the missing column.
    if (!channels_derivable(model, measured)) return {kZeroLag, "the record lacks a state"};
    return {kLagged, "the record lacks a state's column, which they read as a derivative"};
  }
  if (options.multipliers || options.degree > 0 || options.extrapolate) {
    return {kZeroLag, "multipliers, a degree or the sampling bias were asked for"};
  }
  if (record.noise_free) return {kZeroLag, "the record is simulated without noise"};
  if (!record.timed) {
    return {kZeroLag, "the record gives no sample interval, which the lagged equations need"};
  }
  if (!record.described) {
    // Arrays and most instruments' files say nothing of how they were made.
    return {kLagged,
            "a record without metadata is taken as measured: they stay unbiased under white "
            "sensor noise (a record known to be free of noise takes the zero-lag ones, several "
            "times faster, with --method zero-lag or simulate's metadata)"};
  }
  return {kLagged, "a measured record: they stay unbiased under white sensor noise"};
}

bool optimal_weighting(const IdentifyOptions& options,
                       const std::vector<std::optional<double>>& fixed, std::size_t equations) {
  if (options.weighting != Weighting::kAuto) return options.weighting == Weighting::kGmm;
  // The sampling bias is the difference of two estimates by one estimator: each optimal
  // weighting would be its own.
  if (options.extrapolate) return false;
  const auto free =
      static_cast<std::size_t>(std::count(fixed.begin(), fixed.end(), std::optional<double>()));
  return equations > free;
}

std::vector<std::optional<double>> fixed_values(const Model& model,
                                                const std::map<std::string, double>& fixed) {
  std::vector<std::optional<double>> out;
  for (const Declaration& p : model.parameters()) {
    const auto it = fixed.find(p.name);
    if (it != fixed.end()) {
      out.emplace_back(it->second);
    } else if (p.fixed) {
      out.emplace_back(p.value->to_double());
    } else {
      out.emplace_back();
    }
  }
  return out;
}

}  // namespace momentid
