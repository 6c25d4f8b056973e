// The channels of a lagged pass and the window of its lags (lagged_window.hpp).

#include "app/identify/lagged_window.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "app/identify/pass.hpp"
#include "momentid/estimate.hpp"

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

}  // namespace

LaggedChannels lagged_channels(const Model& model, const LaggedSystem& system) {
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
  if (model.functions().empty()) return out;
  const std::vector<ComputedChannel> all = computed_channels(model);
  for (std::size_t u = 0; u < model.variables().size(); ++u) {
    const Variable& variable = model.variables()[u];
    if (variable.channel() || !system.needed[u]) continue;
    const ComputedChannel& function = all[static_cast<std::size_t>(variable.index)];
    ComputedChannel c{.sign = function.sign, .argument = {}};
    for (const auto& [coefficient, monomial] : function.argument) {
      Monomial read(next, 0);
      for (std::size_t v = 0; v < monomial.size(); ++v) {
        if (monomial[v] != 0) read[static_cast<std::size_t>(out.channel[v])] = monomial[v];
      }
      c.argument.emplace_back(coefficient, std::move(read));
    }
    out.computed.push_back(std::move(c));
    out.channel[u] = static_cast<int>(next + out.computed.size() - 1);
  }
  return out;
}

std::map<std::string, int> correlation_lags(const IdentifyResult& r,
                                            const std::vector<int>& channel) {
  const LaggedSystem& system = *r.lagged->system;
  const Model& model = *r.model;
  std::map<Moment, std::size_t> index;
  for (std::size_t k = 0; k < r.lagged->moments.size(); ++k) index.emplace(r.lagged->moments[k], k);
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
    int tau = 0;
    for (int s = system.first_lag; s <= system.last_lag && tau == 0; ++s) {
      const auto it = index.find(lagged_moment(y, y, s));
      if (it == index.end()) continue;
      const double rho = (r.data.estimates.mean[it->second] - c.mean * c.mean) / c.variance;
      if (rho < std::exp(-1.0)) tau = s;
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
