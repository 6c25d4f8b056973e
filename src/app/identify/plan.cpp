#include <algorithm>

#include "app/identify/steps.hpp"

namespace momentid {

EquationKind choose_equations(const Model& model, const std::vector<bool>& measured,
                              const IdentifyOptions& options) {
  const bool all_measured = std::all_of(measured.begin(), measured.end(), [](bool m) { return m; });
  // Without lags asked for, data that cannot show a state (not even as a derivative) get the
  // zero-lag pass and its message naming the missing column.
  if (!options.lags && (all_measured || !derivable_from(model, measured))) {
    return EquationKind::kZeroLag;
  }
  return EquationKind::kLagged;
}

std::vector<std::string> state_names(const Model& model) {
  std::vector<std::string> out;
  for (const auto& d : model.states()) out.push_back(d.name);
  return out;
}

std::vector<std::string> input_names(const Model& model) {
  std::vector<std::string> out;
  for (const auto& d : model.inputs()) out.push_back(d.name);
  return out;
}

DataOptions pass_options(const IdentifyOptions& options) {
  DataOptions data_options;
  data_options.record = options.record;
  data_options.batches = options.batches.value_or(0);
  data_options.min_rows = 2 * (options.batches ? *options.batches : DataOptions::kMinAutoBatches);
  data_options.input_shift = options.input_shift;
  data_options.lags = 4;  // for the noise estimates
  return data_options;
}

std::vector<double> channel_offsets(const DataSource& source,
                                    const std::vector<std::string>& states,
                                    const std::vector<std::string>& inputs,
                                    const DataOptions& options,
                                    const std::vector<std::string>& center,
                                    std::map<std::string, double>& centered) {
  std::vector<std::string> channels = states;
  channels.insert(channels.end(), inputs.begin(), inputs.end());
  centered.clear();
  if (std::none_of(channels.begin(), channels.end(), [&](const std::string& c) {
        return std::find(center.begin(), center.end(), c) != center.end();
      })) {
    return {};
  }
  DataOptions first = options;
  first.offsets.clear();
  const DataMoments means =
      moments_from_data(source, states, inputs, std::vector<Monomial>{}, first);
  std::vector<double> out(channels.size(), 0.0);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    if (std::find(center.begin(), center.end(), channels[c]) == center.end()) continue;
    out[c] = means.channels[c].mean;
    centered[channels[c]] = out[c];
  }
  return out;
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
