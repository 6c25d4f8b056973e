// The channels of a lagged pass and the window of its lags (lagged_window.hpp).

#include "app/identify/lagged_window.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "app/identify/moment_lists.hpp"
#include "app/identify/pass.hpp"
#include "momentid/estimate.hpp"
#include "solve/rows.hpp"

namespace momentid {
namespace {

// The moments the lagged equations for `lag_options` read.
std::size_t moment_count(const Model& model, const LagOptions& lag_options) {
  const LaggedSystem system = derive_lagged(model, lag_options);
  return lagged_rows(system, 1.0, lagged_channels(model, system).channel, {}).moments.size();
}

// `all` cut to `keep` instruments: the linear ones (the measured states) before powers, spread
// evenly over the states when they are more than `keep`.
std::vector<Monomial> fewer_instruments(const std::vector<Monomial>& all, std::size_t keep) {
  std::vector<Monomial> linear, powers;
  for (const Monomial& m : all) {
    (std::accumulate(m.begin(), m.end(), 0) == 1 ? linear : powers).push_back(m);
  }
  std::vector<Monomial> out;
  if (keep <= linear.size()) {
    for (std::size_t i = 0; i < keep; ++i) {
      const std::size_t at = keep == 1 ? 0 : i * (linear.size() - 1) / (keep - 1);
      out.push_back(linear[at]);
    }
    return out;
  }
  out = linear;
  out.insert(out.end(), powers.begin(), powers.begin() + static_cast<long>(keep - linear.size()));
  return out;
}

// The channels of `c`'s products (LaggedChannels::products), which `raw` (per channel read) says
// the filter may take whole.
void add_products(const Model& model, const LaggedSystem& system, const std::vector<bool>& raw,
                  LaggedChannels& c) {
  const std::size_t read = c.states.size() + c.inputs.size() + c.derivatives.size();
  const std::size_t width = std::max(model.variables().size(), read + c.computed.size());
  const std::vector<double> every(read, 1.0);  // every term of the noise corrections
  std::vector<Monomial> found;
  const auto add = [&](const LagCombination& combination) {
    for (const auto& [f, weight] : combination) {
      Monomial function(width, 0);
      for (std::size_t v = 0; v < f.function.size(); ++v) {
        if (f.function[v] != 0) function[static_cast<std::size_t>(c.channel[v])] = f.function[v];
      }
      for (const auto& [term, w] : noise_corrected(function, every)) {
        bool whole = true;
        for (std::size_t k = 0; k < term.size(); ++k) {
          whole &= term[k] == 0 || (k < raw.size() && raw[k]);
        }
        if (whole && term.degree() >= 2 &&
            std::find(found.begin(), found.end(), term) == found.end()) {
          found.push_back(term);
        }
      }
    }
  };
  for (const LaggedEquation& eq : system.equations) {
    add(eq.rhs);
    for (const LagCombination& coefficient : eq.coefficients) add(coefficient);
  }
  if (found.empty()) return;
  // The products widen every monomial over the channels to the channels' count.
  const std::size_t channels = read + c.computed.size() + found.size();
  std::vector<std::string> names = c.states;
  names.insert(names.end(), c.inputs.begin(), c.inputs.end());
  names.insert(names.end(), c.derivatives.begin(), c.derivatives.end());
  for (Monomial& product : found) {
    ComputedChannel computed{.kind = ComputedChannel::Kind::kPolynomial, .argument = {}};
    computed.argument.emplace_back(1.0, Monomial(product.begin(), product.begin() + read));
    std::string name;
    for (std::size_t k = 0; k < read; ++k) {
      if (product[k] == 0) continue;
      if (!name.empty()) name += '*';
      name += names[k];
      if (product[k] > 1) (name += '^') += std::to_string(product[k]);
    }
    c.computed.push_back(std::move(computed));
    c.computed_names.push_back(std::move(name));
    product.resize(std::max(width, channels));
    c.products.emplace(std::move(product), static_cast<int>(read + c.computed.size() - 1));
  }
}

}  // namespace

LaggedChannels lagged_channels(const Model& model, const LaggedSystem& system,
                               const std::optional<IdentifyResult::Integration>& integration) {
  LaggedChannels out;
  out.channel.assign(model.variables().size(), -1);
  std::size_t next = 0;
  for (std::size_t v = 0; v < model.variables().size(); ++v) {
    const Variable& variable = model.variables()[v];
    if (!variable.channel() || !system.needed[v]) continue;
    (variable.kind == VariableKind::kState   ? out.states
     : variable.kind == VariableKind::kInput ? out.inputs
                                             : out.derivatives)
        .push_back(variable.name);
    // The pass numbers its channels in the variables' order.
    out.channel[v] = static_cast<int>(next++);
  }
  const std::vector<ComputedChannel> all = computed_channels(model);
  for (std::size_t u = 0; u < model.variables().size() && !all.empty(); ++u) {
    const Variable& variable = model.variables()[u];
    if (variable.channel() || !system.needed[u]) continue;
    const ComputedChannel& function = all[static_cast<std::size_t>(variable.index)];
    ComputedChannel c{.kind = function.kind, .argument = {}};
    for (const auto& [coefficient, monomial] : function.argument) {
      Monomial read(next, 0);
      for (std::size_t v = 0; v < monomial.size(); ++v) {
        if (monomial[v] != 0) read[static_cast<std::size_t>(out.channel[v])] = monomial[v];
      }
      c.argument.emplace_back(coefficient, std::move(read));
    }
    out.computed.push_back(std::move(c));
    out.computed_names.push_back(variable.name);
    out.channel[u] = static_cast<int>(next + out.computed.size() - 1);
  }
  if (!integration) return out;
  // The measured states that are neither formed nor a formed state's column (whose noise the
  // formed state shares) go through the filter alone.
  std::vector<bool> raw(next, false);
  for (std::size_t v = 0; v < model.states().size(); ++v) {
    const std::string& name = model.variables()[v].name;
    if (out.channel[v] < 0) continue;
    raw[static_cast<std::size_t>(out.channel[v])] =
        std::none_of(integration->formed.begin(), integration->formed.end(),
                     [&](const auto& f) { return f.state == name || f.variable == name; });
  }
  add_products(model, system, raw, out);
  return out;
}

std::map<std::string, int> correlation_lags(const IdentifyResult& r,
                                            const std::vector<int>& channel) {
  const LaggedSystem& system = *r.lagged->system;
  const Model& model = *r.model;
  const std::map<Moment, std::size_t> index = moment_index(r.lagged->moments);
  std::map<std::string, int> out;
  const std::vector<VariableReading> readings = variable_readings(model, system.measured);
  const auto formed_from = [&](const std::string& column) {
    return r.integration && std::any_of(r.integration->formed.begin(), r.integration->formed.end(),
                                        [&](const auto& f) { return f.variable == column; });
  };
  for (std::size_t v = 0; v < model.channel_count(); ++v) {
    const Variable& variable = model.variables()[v];
    // A derivative column counts where its state is read through it, not formed from it.
    const bool stands_for_state =
        variable.kind == VariableKind::kState ||
        (variable.kind == VariableKind::kDerivative && !formed_from(variable.name) &&
         readings[static_cast<std::size_t>(
                      model.measured_derivatives()[static_cast<std::size_t>(variable.index)].state)]
                 .order < 0);
    if (channel[v] < 0 || !system.measured[v] || !stands_for_state) continue;
    const ChannelStatistics& c = r.data.channels[static_cast<std::size_t>(channel[v])];
    if (!(c.variance > 0)) continue;
    Monomial y(channel.size(), 0);
    y[static_cast<std::size_t>(channel[v])] = 1;
    int tau = -1;
    for (int s = system.first_lag; s <= system.last_lag && tau <= 0; ++s) {
      const auto it = index.find(lagged_moment(y, y, s));
      if (it == index.end()) continue;
      const double rho = (r.data.estimates.mean[it->second] - c.mean * c.mean) / c.variance;
      tau = rho < std::exp(-1.0) ? s : 0;
    }
    out[c.name] = tau;
  }
  return out;
}

int lag_window(const IdentifyResult& r) {
  const LaggedSystem& system = *r.lagged->system;
  int wanted = 0;
  for (const auto& [name, tau] : r.lagged->correlation_lags) {
    wanted = std::max(wanted, tau > 0 ? 5 * tau : 4 * system.last_lag);
  }
  if (wanted == 0) return system.last_lag;
  return std::clamp(wanted, system.first_lag + LagOptions::kMinSpan - 1, LagOptions::kMaxLag);
}

int last_lag_within_budget(int first, int last, std::size_t count) {
  const double per_lag = static_cast<double>(count) / (last - first + 1);
  return first - 1 + static_cast<int>(IdentifyOptions::kMaxLaggedMoments / std::max(per_lag, 1.0));
}

std::string fit_to_budget(const Model& model, LagOptions& lag_options,
                          const IdentifyOptions& options) {
  const int first = lag_options.first_lag, default_last = lag_options.last_lag;
  std::size_t count = moment_count(model, lag_options);
  const std::size_t budget = IdentifyOptions::kMaxLaggedMoments;
  if (count <= budget) return "";
  if (!options.lags) {
    lag_options.last_lag = std::max(first + LagOptions::kMinSpan - 1,
                                    last_lag_within_budget(first, default_last, count));
    count = moment_count(model, lag_options);
  }
  std::string cut;
  if (count > budget && !options.instruments) {
    const std::vector<Monomial> all = derive_lagged(model, lag_options).instruments;
    lag_options.instruments = all;
    for (std::size_t keep = all.size() - 1; keep >= 1 && count > budget; --keep) {
      lag_options.instruments = fewer_instruments(all, keep);
      count = moment_count(model, lag_options);
    }
    cut = std::to_string(lag_options.instruments->size()) + " of the " +
          std::to_string(all.size()) + " instruments";
    if (!options.lags && count <= budget) {
      lag_options.last_lag =
          std::min(default_last, last_lag_within_budget(first, lag_options.last_lag, count));
    }
  }
  if (count > budget && !options.lags && !options.instruments) {
    throw Error("the lagged equations of model " + model.name() + " need " + std::to_string(count) +
                " moments with one instrument at lags " + std::to_string(first) + ".." +
                std::to_string(lag_options.last_lag) + ", more than " + std::to_string(budget));
  }
  if (count > budget) {
    const std::string given = options.lags && options.instruments ? "lags and instruments"
                              : options.lags                      ? "lags"
                                                                  : "instruments";
    throw UsageError(options.lags ? "lags" : "instruments",
                     "the " + given + " given need " + std::to_string(count) +
                         " moments, more than " + std::to_string(budget) +
                         ": give fewer lags or instruments");
  }
  return cut;
}

}  // namespace momentid
