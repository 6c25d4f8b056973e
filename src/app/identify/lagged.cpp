// The lagged moment equations (docs/measured-data.md): an instrument at t - s times an
// equation at t, for records that lack a state's column or carry sensor noise.

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <tuple>

#include "app/identify/steps.hpp"
#include "common/number.hpp"

namespace momentid {
namespace {

// Noise on a function's argument above this fraction of the channel's standard deviation is
// reported, as the noise itself is (below it the estimate is at the level of the roughness of
// a state driven through a held input).
constexpr double kNoisyArgument = 0.02;

// Whether channel `c` (a state or input) is in a function's argument.
bool function_holds(const VariableFunction& f, std::size_t c) {
  return std::any_of(f.argument.begin(), f.argument.end(),
                     [&](const auto& term) { return term.second[c] != 0; });
}

// Per measured (or formed) state that the lagged equations read, or derivative column that
// stands for its unmeasured state: the lag at which its autocorrelation first falls below 1/e,
// from the lagged moments C[y;y](s) of the pass; 0 when it stays above across the window.
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

// The last lag that spans five correlation times of the slowest measured state; four times the
// window when a state stays correlated across it. Kept within the bounds of the lag options.
int lag_window(const IdentifyResult& r) {
  const LaggedSystem& system = *r.lagged->system;
  int wanted = 0;
  for (const auto& [name, tau] : r.lagged->correlation_lags) {
    wanted = std::max(wanted, tau > 0 ? 5 * tau : 4 * system.last_lag);
  }
  if (wanted == 0) return system.last_lag;
  return std::clamp(wanted, system.first_lag + LagOptions::kMinSpan - 1, LagOptions::kMaxLag);
}

// Multipliers, a degree and the sampling bias belong to the zero-lag equations.
void check_lagged_options(const Model& model, const IdentifyOptions& options,
                          const std::vector<bool>& measured) {
  if (options.extrapolate) {
    throw UsageError("extrapolate",
                     "the sampling bias is estimated for the zero-lag equations, and these data "
                     "call for the lagged ones");
  }
  if (options.multipliers || options.degree > 0) {
    std::string missing;
    for (std::size_t v = 0; v < measured.size(); ++v) {
      if (!measured[v]) missing += (missing.empty() ? "" : ", ") + model.variables()[v].name;
    }
    const std::string why = options.method == Method::kLagged     ? "the lagged ones were asked for"
                            : options.lags || options.instruments ? "lags or instruments were given"
                                                                  : "the data lack " + missing;
    throw UsageError("multipliers and a degree choose zero-lag equations, but " + why +
                     ": the lagged equations take instruments instead");
  }
}

// The channels a lagged pass reads: the variables the equations need, states, inputs and
// derivatives, as the pass numbers them, then the functions it computes from them.
struct LaggedChannels {
  std::vector<std::string> states, inputs, derivatives;
  std::vector<ComputedChannel> computed;  // over the channels read
  std::vector<int> channel;               // per model variable: its channel, or -1 when not read
};

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

// The warnings for functions whose argument holds a noisy channel: the Hermite correction
// replaces powers of a channel, and no polynomial corrects |y + e| or sign(y + e).
std::vector<std::string> noisy_function_warnings(const IdentifyResult& result,
                                                 const LaggedChannels& c) {
  const Model& model = *result.model;
  std::vector<std::string> out;
  for (std::size_t u = 0; u < model.variables().size(); ++u) {
    const Variable& variable = model.variables()[u];
    if (variable.channel() || c.channel[u] < 0) continue;
    const VariableFunction& f = model.function_of(variable);
    for (std::size_t v = 0; v < model.states().size(); ++v) {
      const int read = c.channel[v];
      if (read < 0 || !function_holds(f, v)) continue;
      const ChannelStatistics& s = result.data.channels[static_cast<std::size_t>(read)];
      const std::optional<double> fraction = s.noise_fraction();
      if (!(result.lagged->noise[static_cast<std::size_t>(read)] > 0) || !fraction ||
          *fraction < kNoisyArgument) {
        continue;
      }
      std::string w = "'" + s.name + "' carries noise of about " + number(100 * *fraction, "%.2g");
      w += "% of its standard deviation, and the lagged equations compute " + f.name;
      w += " from it: no correction removes noise from inside abs or sign, and the terms with ";
      w += f.name + " are biased (docs/measured-data.md, \"abs and sign of noisy channels\")";
      out.push_back(std::move(w));
    }
  }
  return out;
}

// The moments the lagged equations for `lag_options` read.
std::size_t moment_count(const Model& model, const LagOptions& lag_options) {
  const LaggedSystem system = derive_lagged(model, lag_options);
  return lagged_rows(system, 1.0, lagged_channels(model, system).channel, {}).moments.size();
}

// The last lag at which `count` moments over lags first..last would stay within the budget,
// taking them to grow in proportion to the number of lags.
int last_lag_within_budget(int first, int last, std::size_t count) {
  const double per_lag = static_cast<double>(count) / (last - first + 1);
  return first - 1 + static_cast<int>(IdentifyOptions::kMaxLaggedMoments / std::max(per_lag, 1.0));
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

// Fits the lags and instruments of `lag_options` to IdentifyOptions::kMaxLaggedMoments where the
// user left them to identify: the window shrinks first, to no fewer than LagOptions::kMinSpan
// lags, then instruments go (powers first) until that window fits, which then grows again as
// far as the budget allows. Returns the instruments cut ("4 of the 10 instruments"), or empty;
// throws UsageError naming the options the user gave when these alone exceed the budget.
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

// Derives the equations for the lags of `lag_options` and makes the pass over the data into
// `result`, reading the zero-lag check's moments as well when `check` plans one (into
// `check_moments`; the check is dropped when the pass does not read a variable it needs).
LaggedChannels read_lagged(IdentifyResult& result, const LagOptions& lag_options,
                           const DataSource& source, const IdentifyOptions& options,
                           std::optional<ZeroLagCheckPlan>& check, MomentEstimates& check_moments) {
  result.lagged = IdentifyResult::Lagged{};
  result.lagged->system =
      std::make_shared<const LaggedSystem>(derive_lagged(*result.model, lag_options));
  LaggedChannels c = lagged_channels(*result.model, *result.lagged->system);
  result.lagged->channels = c.states;
  result.lagged->channels.insert(result.lagged->channels.end(), c.inputs.begin(), c.inputs.end());
  result.lagged->channels.insert(result.lagged->channels.end(), c.derivatives.begin(),
                                 c.derivatives.end());
  // The rows need the sample interval, which the data give: accumulate, then build rows.
  const LaggedRows probe = lagged_rows(*result.lagged->system, 1.0, c.channel, {});
  result.lagged->moments = probe.moments;
  // The channels' means come with the pass.
  std::vector<Moment> moments = probe.moments;
  std::vector<std::size_t> mean_index;
  for (const Monomial& m : first_moments_of(result.lagged->channels.size())) {
    const Moment mean = Moment::from_monomial(m);
    const auto found = std::find(moments.begin(), moments.end(), mean);
    mean_index.push_back(static_cast<std::size_t>(found - moments.begin()));
    if (found == moments.end()) moments.push_back(mean);
  }
  std::vector<std::size_t> check_index;
  if (check && std::all_of(check->moments.begin(), check->moments.end(), [&](const Monomial& m) {
        for (std::size_t v = 0; v < m.size(); ++v) {
          if (m[v] != 0 && c.channel[v] < 0) return false;
        }
        return true;
      })) {
    std::map<Moment, std::size_t> at;
    for (std::size_t k = 0; k < moments.size(); ++k) at.emplace(moments[k], k);
    for (const Monomial& m : check->moments) {
      Monomial read(result.lagged->channels.size() + c.computed.size(), 0);
      for (std::size_t v = 0; v < m.size(); ++v) {
        if (m[v] != 0) read[static_cast<std::size_t>(c.channel[v])] = m[v];
      }
      const Moment moment = m.rate() ? Moment::increment_of(read) : Moment::from_monomial(read);
      const auto [it, added] = at.emplace(moment, moments.size());
      if (added) moments.push_back(it->first);
      check_index.push_back(it->second);
    }
  } else {
    check.reset();
  }
  DataOptions data_options = pass_options(*result.model, options);
  data_options.derivatives = c.derivatives;
  if (const auto& integration = result.integration) {
    data_options.integration = DataOptions::Integration{
        .corner = integration->corner, .dt = integration->dt, .integrals = {}};
    DataOptions::Integration& f = *data_options.integration;
    for (const std::string& name : result.lagged->channels) {
      int integrals = 0;
      for (const auto& formed : integration->formed) {
        if (formed.state == name) {
          integrals = formed.integrals;
          data_options.record.columns[name] = formed.column;
        }
      }
      f.integrals.push_back(integrals);
    }
  }
  // The optimal weighting estimates the equations' covariance from the batches.
  data_options.min_batches = kBatchesPerEquation * probe.rows.a.size();
  data_options.offsets =
      channel_offsets(source, c.states, c.inputs, data_options, options.center, result.centered);
  data_options.computed = c.computed;
  result.data = moments_from_data(source, c.states, c.inputs, moments, data_options);
  result.means = channel_means(result.lagged->channels, result.data.estimates, mean_index);
  add_end_errors(result.means, *result.model, result.data);
  if (check) check_moments = moments_at(result.data.estimates, check_index);
  result.data.estimates = first_moments(result.data.estimates, probe.moments.size());
  if (!result.data.time_step) {
    throw DataError({source.name(), 1, 1, ""},
                    "the lagged equations need the sample interval: give the data a 't' "
                    "column or a dt in the metadata");
  }
  result.lagged->correlation_lags = correlation_lags(result, c.channel);
  return c;
}

// The noise on each channel of a state or a derivative: given, or estimated from its
// autocorrelation (inputs are taken as measured without noise).
std::vector<double> noise_variances(const IdentifyResult& result, const LaggedChannels& channels,
                                    const IdentifyOptions& options) {
  std::vector<double> noise(result.lagged->channels.size(), 0.0);
  const std::size_t states = channels.states.size(), inputs = channels.inputs.size();
  for (std::size_t c = 0; c < noise.size(); ++c) {
    if (c >= states && c < states + inputs) continue;
    if (options.noise) {
      const auto given = options.noise->find(result.lagged->channels[c]);
      if (given != options.noise->end()) noise[c] = given->second;
    } else if (const auto& v = result.data.channels[c].noise_variance) {
      noise[c] = std::max(0.0, *v);
    }
  }
  // A formed state's noise is its column's, through the filter: colored, so that its
  // autocorrelation does not show it.
  if (const auto& integration = result.integration) {
    const std::vector<std::string>& names = result.lagged->channels;
    const auto at = [&](const std::string& name) {
      return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
    };
    for (const auto& formed : integration->formed) {
      const std::size_t state = at(formed.state), column = at(formed.variable);
      if (state >= noise.size() || column >= noise.size()) continue;
      if (options.noise && options.noise->count(formed.state)) continue;
      noise[state] = noise[column] * formed.noise_gain;
    }
  }
  return noise;
}

// The accuracy floor of the lagged moments (docs/measured-data.md, "The accuracy floor"): the
// variance of an error of kAccuracyFloor times the largest magnitude that the pair psi, F
// reaches over the lags, for each E[psi(t - s) F(t)], as if independent.
constexpr double kAccuracyFloor = 1e-6;

std::vector<double> accuracy_floor(const std::vector<Moment>& moments,
                                   const std::vector<double>& mean) {
  const auto pair_of = [](const Moment& m) {
    std::vector<MomentFactor> key = m.factors();
    for (MomentFactor& f : key) f.lag = std::min(f.lag, 1);
    return key;
  };
  std::map<std::vector<MomentFactor>, double> peak;
  for (std::size_t k = 0; k < moments.size(); ++k) {
    double& p = peak[pair_of(moments[k])];
    p = std::max(p, std::abs(mean[k]));
  }
  std::vector<double> variance(moments.size());
  for (std::size_t k = 0; k < moments.size(); ++k) {
    const double floor = kAccuracyFloor * peak[pair_of(moments[k])];
    variance[k] = floor * floor;
  }
  return variance;
}

}  // namespace

MomentRows lagged_rows_of(const IdentifyResult& result, const LaggedSystem& system) {
  const LaggedChannels channels = lagged_channels(*result.model, *result.lagged->system);
  LaggedRows rows = lagged_rows(system, *result.data.time_step, channels.channel,
                                result.lagged->noise, result.lagged->stencil_reach);
  std::map<Moment, std::size_t> index;
  for (std::size_t k = 0; k < result.lagged->moments.size(); ++k) {
    index.emplace(result.lagged->moments[k], k);
  }
  const auto reindex = [&](MomentRows::Entry& entry) {
    for (auto& [k, weight] : entry.moments) k = index.at(rows.moments[k]);
  };
  for (auto& row : rows.rows.a) {
    for (MomentRows::Entry& entry : row) reindex(entry);
  }
  for (MomentRows::Entry& entry : rows.rows.b) reindex(entry);
  return std::move(rows.rows);
}

void identify_lagged(IdentifyResult& result, const DataSource& source,
                     const IdentifyOptions& options, const std::vector<bool>& measured) {
  const Model& model = *result.model;
  check_lagged_options(model, options, measured);
  LagOptions lag_options;
  if (options.lags) std::tie(lag_options.first_lag, lag_options.last_lag) = *options.lags;
  lag_options.instruments = options.instruments;
  lag_options.measured = measured;
  if (result.integration && !options.instruments) {
    // The formed states carry the integral of the column's noise, slow and correlated across
    // every lag: the columns they are formed from are the instruments, their noise white.
    lag_options.instruments.emplace();
    for (const auto& formed : result.integration->formed) {
      Monomial m(model.variables().size(), 0);
      m[static_cast<std::size_t>(model.variable_index(formed.variable))] = 1;
      if (std::find(lag_options.instruments->begin(), lag_options.instruments->end(), m) ==
          lag_options.instruments->end()) {
        lag_options.instruments->push_back(m);
      }
    }
  }
  const std::string instruments_cut = fit_to_budget(model, lag_options, options);
  std::optional<ZeroLagCheckPlan> check = plan_zero_lag_check(model, options, measured);
  MomentEstimates check_moments;
  LaggedChannels channels = read_lagged(result, lag_options, source, options, check, check_moments);
  // The default lags span about five correlation times of the measured states: when the
  // first pass shows them far from that (more than 1.5 times longer or 2 times shorter), a
  // second pass takes the lags the data call for, as far as the budget allows.
  std::string window_cut;
  if (!options.lags) {
    const LaggedSystem& system = *result.lagged->system;
    const int wanted = lag_window(result);
    const int most =
        last_lag_within_budget(system.first_lag, system.last_lag, result.lagged->moments.size());
    const int last = system.last_lag;
    const int granted =
        std::max(std::min(wanted, most), system.first_lag + LagOptions::kMinSpan - 1);
    if (2 * granted > 3 * last || 2 * granted < last) {
      lag_options.last_lag = granted;
      channels = read_lagged(result, lag_options, source, options, check, check_moments);
    }
    if (wanted > 3 * result.lagged->system->last_lag / 2) {
      window_cut = "lags " + std::to_string(result.lagged->system->first_lag) + ".." +
                   std::to_string(result.lagged->system->last_lag) +
                   " (the correlation times call for .." + std::to_string(wanted) + ")";
    }
  }
  if (!instruments_cut.empty() || !window_cut.empty()) {
    result.lagged->cut = "cut to " + instruments_cut +
                         (instruments_cut.empty() || window_cut.empty() ? "" : " and ") +
                         window_cut + " to stay within " +
                         std::to_string(IdentifyOptions::kMaxLaggedMoments) + " moments";
  }
  result.lagged->noise = noise_variances(result, channels, options);
  // The moments name the computed channels after the channels read (lagged_moment_text).
  for (std::size_t v = 0; v < channels.channel.size(); ++v) {
    const Variable& variable = result.model->variables()[v];
    if (!variable.channel() && channels.channel[v] >= 0) {
      result.lagged->channels.push_back(variable.name);
    }
  }
  // Inputs held over each sample put kinks into the states at the samples, which only the
  // five-point stencils match; band-limited records take the wide ones.
  result.lagged->stencil_reach =
      result.data.hold == InputHold::kSample ? kWideStencilReach : kStencilReach;
  const LaggedRows rows =
      lagged_rows(*result.lagged->system, *result.data.time_step, channels.channel,
                  result.lagged->noise, result.lagged->stencil_reach);
  std::vector<std::string> names;
  for (const Declaration& p : model.parameters()) names.push_back(p.name);
  result.gmm = optimal_weighting(model, options, rows.rows.a.size());
  result.lagged->moment_variance =
      accuracy_floor(result.lagged->moments, result.data.estimates.mean);
  result.estimate = solve_rows(rows.rows, names, result.data.estimates,
                               {.gmm = result.gmm,
                                .fixed = fixed_values(model, options.fixed),
                                .normalise_rows = true,
                                .moment_variance = result.lagged->moment_variance});
  if (check && result.estimate.j_pvalue) {
    check_with_zero_lag(result, *check, check_moments, channels.channel, options);
  }
  const std::vector<std::string> noisy = noisy_function_warnings(result, channels);
  result.estimate.warnings.insert(result.estimate.warnings.end(), noisy.begin(), noisy.end());
  if (const auto& integration = result.integration) {
    for (const auto& formed : integration->formed) {
      result.estimate.warnings.push_back(
          "'" + formed.state + "' was formed from '" + formed.column + "' inside a high-pass at " +
          number(integration->corner, "%.3g") +
          " Hz: the terms nonlinear in it lose the low frequencies the filter cuts, which "
          "biases the estimates (a stiffness by a few percent), and the intervals do not "
          "include that bias "
          "(docs/model-language.md, \"Forming a state from its acceleration\")");
    }
  }
}

}  // namespace momentid
