// The channels and options of a pass over the record, as the steps of identify() ask for it.

#include "app/identify/pass.hpp"

#include <algorithm>

namespace momentid {

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

std::vector<ComputedChannel> computed_channels(const Model& model) {
  std::vector<ComputedChannel> out;
  for (const VariableFunction& f : model.functions()) {
    ComputedChannel c{.kind = f.kind == FunctionKind::kSign ? ComputedChannel::Kind::kSign
                                                            : ComputedChannel::Kind::kAbs,
                      .argument = {}};
    bool of_states = false, of_inputs = false;
    for (const auto& [coefficient, monomial] : f.argument) {
      c.argument.emplace_back(coefficient.to_double(), monomial);
      for (std::size_t i = 0; i < monomial.size(); ++i) {
        if (monomial[i] == 0) continue;
        (model.variables()[i].kind == VariableKind::kState ? of_states : of_inputs) = true;
      }
    }
    if (of_states && of_inputs) {
      // Some term holds it: check_model refuses a function that cancels.
      const Equation* holding = nullptr;
      const auto v = static_cast<std::size_t>(model.variable_index(f.name));
      for (const Equation& eq : model.equations()) {
        for (const Term& t : eq.terms) {
          if (!holding && t.monomial[v] != 0) holding = &eq;
        }
      }
      throw ModelError(holding->where, f.name +
                                           " mixes states and inputs: identify takes abs "
                                           "and sign of the states alone or of the inputs "
                                           "alone");
    }
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<std::string> derivative_names(const Model& model) {
  std::vector<std::string> out;
  for (const MeasuredDerivative& d : model.measured_derivatives()) out.push_back(d.name);
  return out;
}

DataOptions pass_options(const Model& model, const IdentifyOptions& options) {
  DataOptions data_options;
  data_options.derivatives = derivative_names(model);
  data_options.record = options.record;
  data_options.batches = options.batches.value_or(0);
  data_options.min_rows = 2 * (options.batches ? *options.batches : DataOptions::kMinAutoBatches);
  data_options.input_shift = options.input_shift;
  data_options.lags = 4;  // for the noise estimates of held inputs
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
  channels.insert(channels.end(), options.derivatives.begin(), options.derivatives.end());
  centered.clear();
  // A derivative column's mean is its sensor's offset, as a stationary state's derivative has
  // mean 0; the integration filter takes offsets out itself.
  const auto removed = [&](std::size_t c) {
    return std::find(center.begin(), center.end(), channels[c]) != center.end() ||
           (c >= states.size() + inputs.size() && !options.integration);
  };
  bool any = false;
  for (std::size_t c = 0; c < channels.size(); ++c) any = any || removed(c);
  if (!any) return {};
  DataOptions first = options;
  first.offsets.clear();
  const DataMoments means =
      moments_from_data(source, states, inputs, std::vector<Monomial>{}, first);
  std::vector<double> out(channels.size(), 0.0);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    if (!removed(c)) continue;
    out[c] = means.channels[c].mean;
    centered[channels[c]] = out[c];
  }
  return out;
}

}  // namespace momentid
