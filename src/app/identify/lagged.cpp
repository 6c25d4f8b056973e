// The lagged moment equations (docs/measured-data.md): an instrument at t - s times an
// equation at t, for records that lack a state's column or carry sensor noise.

#include "app/identify/lagged.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <optional>
#include <tuple>

#include "app/identify/channel_means.hpp"
#include "app/identify/lagged_window.hpp"
#include "app/identify/moment_lists.hpp"
#include "app/identify/pass.hpp"
#include "app/identify/plan.hpp"
#include "app/identify/response_record.hpp"
#include "app/identify/zero_lag_check.hpp"
#include "common/number.hpp"
#include "moments/integration.hpp"

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

// Whether the equations hold state v nonlinearly: in a product of degree 2 or more, or in the
// argument of an abs or sign; with `apart`, only in terms for which apart(term) holds.
bool nonlinear_in(const Model& model, const LaggedSystem& system, std::size_t v,
                  const std::function<bool(const Monomial&)>& apart = nullptr) {
  const auto nonlinear = [&](const LagCombination& c) {
    return std::any_of(c.begin(), c.end(), [&](const auto& entry) {
      const Monomial& m = entry.first.function;
      if (apart && !apart(m)) return false;
      int degree = 0;
      bool holds = false;
      for (std::size_t u = 0; u < m.size(); ++u) {
        if (m[u] == 0) continue;
        degree += m[u];
        const Variable& variable = model.variables()[u];
        if (u == v) {
          holds = true;
        } else if (!variable.channel() && function_holds(model.function_of(variable), v)) {
          holds = true;
          degree += 1;  // nonlinear in v by itself
        }
      }
      return holds && degree >= 2;
    });
  };
  return std::any_of(
      system.equations.begin(), system.equations.end(), [&](const LaggedEquation& eq) {
        return nonlinear(eq.rhs) ||
               std::any_of(eq.coefficients.begin(), eq.coefficients.end(), nonlinear);
      });
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

// What the options and the record's survey decide before the pass, computed once and read by
// every step (the window may still change after the first pass: fit_window).
struct LaggedPlan {
  LagOptions lags;              // the window and instruments, fitted to the moment budget
  std::string instruments_cut;  // "4 of the 10 instruments" when the budget cut them, or empty
  std::optional<ZeroLagCheckPlan> check;
  std::vector<std::optional<double>> fixed;  // per parameter (fixed_values)
};

LaggedPlan plan_lagged(const Model& model, const IdentifyOptions& options,
                       const std::vector<bool>& measured,
                       const std::optional<IdentifyResult::Integration>& integration) {
  check_lagged_options(model, options, measured);
  LaggedPlan plan;
  if (options.lags) std::tie(plan.lags.first_lag, plan.lags.last_lag) = *options.lags;
  plan.lags.instruments = options.instruments;
  plan.lags.measured = measured;
  if (integration && !options.instruments) {
    // The formed states carry the integral of the column's noise, slow and correlated across
    // every lag: the columns they are formed from are the instruments, their noise white.
    std::vector<Monomial>& instruments = plan.lags.instruments.emplace();
    for (const auto& formed : integration->formed) {
      Monomial m(model.variables().size(), 0);
      m[static_cast<std::size_t>(model.variable_index(formed.variable))] = 1;
      if (std::find(instruments.begin(), instruments.end(), m) == instruments.end()) {
        instruments.push_back(m);
      }
    }
  }
  plan.instruments_cut = fit_to_budget(model, plan.lags, options);
  plan.check = plan_zero_lag_check(model, options, measured);
  plan.fixed = fixed_values(model, options.fixed);
  return plan;
}

// What a lagged pass read beside result.data: its channels, and the zero-lag check's moments
// when the plan has a check and the pass reads every variable it needs.
struct LaggedPass {
  LaggedChannels channels;
  std::optional<MomentEstimates> check_moments;
};

// What a lagged pass reads: the equations' moments, then the channels' means and the zero-lag
// check's moments where these are not among them, with the index of each of these.
struct PassMoments {
  std::vector<Moment> moments;
  std::vector<std::size_t> mean_index;   // per channel
  std::vector<std::size_t> check_index;  // per moment of the check's plan
  bool read_check = false;  // the plan has a check, and the pass reads every variable it needs
};

PassMoments pass_moments(const IdentifyResult& result, const LaggedChannels& c,
                         const std::vector<Moment>& equations,
                         const std::optional<ZeroLagCheckPlan>& check) {
  PassMoments out{equations, {}, {}, false};
  std::vector<Moment>& moments = out.moments;
  for (const Monomial& m : first_moments_of(result.lagged->channels.size())) {
    const Moment mean = Moment::from_monomial(m);
    const auto found = std::find(moments.begin(), moments.end(), mean);
    out.mean_index.push_back(static_cast<std::size_t>(found - moments.begin()));
    if (found == moments.end()) moments.push_back(mean);
  }
  out.read_check =
      check && std::all_of(check->moments.begin(), check->moments.end(), [&](const Monomial& m) {
        for (std::size_t v = 0; v < m.size(); ++v) {
          if (m[v] != 0 && c.channel[v] < 0) return false;
        }
        return true;
      });
  if (!out.read_check) return out;
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
    out.check_index.push_back(it->second);
  }
  return out;
}

// The channels a lagged pass reads, by name: the states, the inputs, the derivatives.
std::vector<std::string> read_channel_names(const LaggedChannels& c) {
  std::vector<std::string> out = c.states;
  out.insert(out.end(), c.inputs.begin(), c.inputs.end());
  out.insert(out.end(), c.derivatives.begin(), c.derivatives.end());
  return out;
}

// The options of a lagged pass but for the offsets: the derivative columns, the integration
// filter of the formed states (each read from its column), the batches the optimal weighting
// needs for `equations` equations, the computed channels.
DataOptions lagged_options(const IdentifyResult& result, const LaggedChannels& c,
                           std::size_t equations, const IdentifyOptions& options) {
  DataOptions data_options = pass_options(*result.model, options);
  data_options.derivatives = c.derivatives;
  if (const auto& integration = result.integration) {
    data_options.integration = DataOptions::Integration{
        .corner = integration->corner, .dt = integration->dt, .integrals = {}};
    DataOptions::Integration& f = *data_options.integration;
    for (const std::string& name : read_channel_names(c)) {
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
  data_options.min_batches = kBatchesPerEquation * equations;
  data_options.computed = c.computed;
  return data_options;
}

// The options of the record's lagged pass: lagged_options and the channels' offsets.
DataOptions lagged_pass_options(IdentifyResult& result, const LaggedChannels& c,
                                std::size_t equations, const DataSource& source,
                                const IdentifyOptions& options) {
  DataOptions data_options = lagged_options(result, c, equations, options);
  data_options.offsets =
      channel_offsets(source, c.states, c.inputs, data_options, options.center, result.centered);
  return data_options;
}

// The noise each formed state shares with the column it is formed from: both channels carry the
// column's white noise, through the filter's taps for their integrals, with the variance of the
// column's filtered noise `noise` (empty: 0, before the pass) over the filter's gain.
SharedNoise shared_noise(const IdentifyResult& result, const LaggedChannels& c,
                         const std::vector<double>& noise) {
  SharedNoise out;
  if (!result.integration) return out;
  const IdentifyResult::Integration& integration = *result.integration;
  // Before the pass (no variances) the sources alone decide which moments the corrections add.
  std::optional<IntegrationFilter> filter;
  if (!noise.empty()) {
    filter.emplace(DataOptions::Integration{
        .corner = integration.corner, .dt = integration.dt, .integrals = {0, 1, 2}});
  }
  const std::size_t channels = c.states.size() + c.inputs.size() + c.derivatives.size();
  out.source.assign(channels, -1);
  out.taps.resize(channels);
  const auto channel_of = [&](const std::string& name) {
    return c.channel[static_cast<std::size_t>(result.model->variable_index(name))];
  };
  for (const auto& formed : integration.formed) {
    const int column = channel_of(formed.variable), state = channel_of(formed.state);
    if (column < 0 || state < 0) continue;
    const auto at = static_cast<std::size_t>(column);
    if (out.source[at] < 0) {
      out.source[at] = static_cast<int>(out.variance.size());
      out.variance.push_back(filter && at < noise.size() ? noise[at] / filter->noise_gain(0) : 0.0);
      if (filter) out.taps[at] = filter->taps(0);
    }
    out.source[static_cast<std::size_t>(state)] = out.source[at];
    if (filter) {
      out.taps[static_cast<std::size_t>(state)] =
          filter->taps(static_cast<std::size_t>(formed.integrals));
    }
  }
  return out;
}

// The equations of `system` before the pass has given the sample interval and the noise: the
// moments they read.
LaggedRows rows_before_the_pass(const IdentifyResult& result, const LaggedSystem& system,
                                const LaggedChannels& c) {
  return lagged_rows(system, 1.0, c.channel, {}, kStencilReach, shared_noise(result, c, {}),
                     c.products);
}

// Derives the equations for the plan's lags and makes the pass over the data into `result`,
// reading the zero-lag check's moments as well when the plan has a check.
LaggedPass read_lagged(IdentifyResult& result, const LaggedPlan& plan, const DataSource& source,
                       const IdentifyOptions& options) {
  result.lagged = IdentifyResult::Lagged{};
  result.lagged->system =
      std::make_shared<const LaggedSystem>(derive_lagged(*result.model, plan.lags));
  LaggedChannels c = lagged_channels(*result.model, *result.lagged->system, result.integration);
  result.lagged->channels = read_channel_names(c);
  // The rows need the sample interval, which the data give: accumulate, then build rows.
  const LaggedRows probe = rows_before_the_pass(result, *result.lagged->system, c);
  result.lagged->moments = probe.moments;
  const PassMoments read = pass_moments(result, c, probe.moments, plan.check);
  const DataOptions data_options =
      lagged_pass_options(result, c, probe.rows.a.size(), source, options);
  result.data = moments_from_data(source, c.states, c.inputs, read.moments, data_options);
  // The channels' means come with the pass.
  result.means = channel_means(result.lagged->channels, result.data.estimates, read.mean_index);
  add_end_errors(result.means, *result.model, result.data);
  LaggedPass pass{std::move(c), std::nullopt};
  if (read.read_check) pass.check_moments = moments_at(result.data.estimates, read.check_index);
  result.data.estimates = first_moments(result.data.estimates, probe.moments.size());
  if (!result.data.time_step) {
    throw DataError({source.name(), 1, 1, ""},
                    "the lagged equations need the sample interval: give the data a 't' "
                    "column or a dt in the metadata");
  }
  result.lagged->correlation_lags = correlation_lags(result, pass.channels.channel);
  return pass;
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

// A channel carries sensor noise when its noise variance (given, estimated, or a formed state's
// through the filter) exceeds this share of its variance: a noise amplitude of 1e-4, above a
// 16-bit converter's rounding.
constexpr double kNoiseShare = 1e-8;

// Per channel of the pass (the channels read, then the computed ones): whether it carries sensor
// noise, a computed channel when one of its arguments does.
std::vector<bool> noisy_channels(const IdentifyResult& result, const LaggedChannels& channels) {
  const std::vector<double>& noise = result.lagged->noise;
  std::vector<bool> out(noise.size() + channels.computed.size(), false);
  for (std::size_t c = 0; c < noise.size(); ++c) {
    out[c] = noise[c] > kNoiseShare * result.data.channels[c].variance;
  }
  for (std::size_t k = 0; k < channels.computed.size(); ++k) {
    for (const auto& [coefficient, monomial] : channels.computed[k].argument) {
      for (std::size_t c = 0; c < std::min(monomial.size(), noise.size()); ++c) {
        if (monomial[c] != 0 && out[c]) out[noise.size() + k] = true;
      }
    }
  }
  return out;
}

// The accuracy floor of the lagged moments (docs/measured-data.md, "The accuracy floor"): the
// variance of an error of kAccuracyFloor times the largest magnitude that the pair psi, F
// reaches over the lags, for each E[psi(t - s) F(t)] none of whose channels is `noisy`, as if
// independent. A moment of a noisy channel has none: its sampling error covers the stencils'
// error, and an error independent from lag to lag would outweigh it in the directions where
// the sampling error is smooth across the lags (a formed state's noise), leaving the J test
// nothing to see there.
constexpr double kAccuracyFloor = 1e-6;

std::vector<double> accuracy_floor(const std::vector<Moment>& moments,
                                   const std::vector<double>& mean,
                                   const std::vector<bool>& noisy) {
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
  std::vector<double> variance(moments.size(), 0.0);
  for (std::size_t k = 0; k < moments.size(); ++k) {
    const std::vector<MomentFactor> factors = moments[k].factors();
    if (std::any_of(factors.begin(), factors.end(), [&](const MomentFactor& f) {
          return static_cast<std::size_t>(f.channel) < noisy.size() &&
                 noisy[static_cast<std::size_t>(f.channel)];
        })) {
      continue;
    }
    const double floor = kAccuracyFloor * peak[pair_of(moments[k])];
    variance[k] = floor * floor;
  }
  return variance;
}

// The equations of `system` at the pass's channels with the noise `noise` on each, less the
// misfit taken out of the result's own (Lagged::misfit).
LaggedRows equations_of(const IdentifyResult& result, const LaggedSystem& system,
                        const LaggedChannels& channels, const std::vector<double>& noise) {
  LaggedRows rows =
      lagged_rows(system, *result.data.time_step, channels.channel, noise,
                  result.lagged->stencil_reach, result.lagged->shared_noise, channels.products);
  if (&system == result.lagged->system.get()) {
    for (std::size_t r = 0; r < result.lagged->misfit.size(); ++r) {
      rows.rows.b[r].constant += result.lagged->misfit[r];
    }
  }
  return rows;
}

}  // namespace

MomentRows lagged_rows_of(const IdentifyResult& result, const LaggedSystem& system) {
  const LaggedChannels channels =
      lagged_channels(*result.model, *result.lagged->system, result.integration);
  LaggedRows rows = equations_of(result, system, channels, result.lagged->noise);
  const std::map<Moment, std::size_t> index = moment_index(result.lagged->moments);
  const auto reindex = [&](MomentRows::Entry& entry) {
    for (auto& [k, weight] : entry.moments) k = index.at(rows.moments[k]);
  };
  for (auto& row : rows.rows.a) {
    for (MomentRows::Entry& entry : row) reindex(entry);
  }
  for (MomentRows::Entry& entry : rows.rows.b) reindex(entry);
  return std::move(rows.rows);
}

namespace {

// The equations of `plan`'s narrower window read the same instruments at fewer lags: a subset of
// the moments the pass read, which are taken from it without reading the record again. Returns
// false (and changes nothing) if the pass lacks one of them.
bool narrow_window(IdentifyResult& result, const LaggedPlan& plan, LaggedPass& pass) {
  auto system = std::make_shared<const LaggedSystem>(derive_lagged(*result.model, plan.lags));
  LaggedChannels c = lagged_channels(*result.model, *system, result.integration);
  if (c.states != pass.channels.states || c.inputs != pass.channels.inputs ||
      c.derivatives != pass.channels.derivatives) {
    return false;
  }
  const LaggedRows probe = rows_before_the_pass(result, *system, c);
  const std::map<Moment, std::size_t> index = moment_index(result.lagged->moments);
  std::vector<std::size_t> at;
  for (const Moment& m : probe.moments) {
    const auto it = index.find(m);
    if (it == index.end()) return false;
    at.push_back(it->second);
  }
  result.data.estimates = moments_at(result.data.estimates, at);
  result.lagged->moments = probe.moments;
  result.lagged->system = std::move(system);
  pass.channels = std::move(c);
  return true;
}

// The default lags span about five correlation times of the measured states, as far as the
// budget allows: a window shorter than the first pass's is taken from its moments, one more than
// 1.5 times longer by a second pass. Returns the window's cut ("lags 3..300 (the correlation
// times call for ..600)") when the budget kept it short.
std::string fit_window(IdentifyResult& result, LaggedPlan& plan, LaggedPass& pass,
                       const DataSource& source, const IdentifyOptions& options) {
  const LaggedSystem& system = *result.lagged->system;
  const int wanted = lag_window(result);
  const int most =
      last_lag_within_budget(system.first_lag, system.last_lag, result.lagged->moments.size());
  const int last = system.last_lag;
  const int granted = std::max(std::min(wanted, most), system.first_lag + LagOptions::kMinSpan - 1);
  if (granted < last) {
    plan.lags.last_lag = granted;
    if (!narrow_window(result, plan, pass)) pass = read_lagged(result, plan, source, options);
  } else if (2 * granted > 3 * last) {
    plan.lags.last_lag = granted;
    pass = read_lagged(result, plan, source, options);
  }
  if (wanted <= 3 * result.lagged->system->last_lag / 2) return "";
  return "lags " + std::to_string(result.lagged->system->first_lag) + ".." +
         std::to_string(result.lagged->system->last_lag) + " (the correlation times call for .." +
         std::to_string(wanted) + ")";
}

// The noise on channel `c` that its fourth differences show, from the autocovariances at lags
// 0..4 (ChannelStatistics::autocorrelation): their mean square over 70, the sum of the squares of
// their weights. It weighs a signal's spectrum by (2 sin(w/2))^8 / 70, 1.5 to 4 times the sixth
// difference's weight from a fifth of the sample rate to a third, and white noise alike.
std::optional<double> fourth_difference_noise(const ChannelStatistics& c) {
  if (c.autocorrelation.size() < 4 || !(c.variance > 0)) return std::nullopt;
  const std::vector<double>& rho = c.autocorrelation;
  return c.variance * (70 - 112 * rho[0] + 56 * rho[1] - 16 * rho[2] + 2 * rho[3]) / 70;
}

// `fit` with the spread of a parameter error uniform along `range` (the estimates' change over
// it) added to its covariance: range range' / 12.
void add_uniform_spread(Fit& fit, const std::vector<double>& range) {
  const std::vector<std::vector<double>> covariance = fit.covariance();
  const std::size_t n = fit.parameters.size();
  for (std::size_t i = 0; i < n; ++i) {
    ParameterEstimate& e = fit.parameters[i];
    if (e.fixed || !(e.std_error > 0)) continue;
    const double t = (e.ci_high - e.estimate) / e.std_error;
    e.std_error = std::sqrt(covariance[i][i] + range[i] * range[i] / 12);
    e.ci_low = e.estimate - t * e.std_error;
    e.ci_high = e.estimate + t * e.std_error;
  }
  for (std::size_t i = 0; i < n && !fit.correlation.empty(); ++i) {
    for (std::size_t k = 0; k < n; ++k) {
      const double si = fit.parameters[i].std_error, sk = fit.parameters[k].std_error;
      if (i != k && si > 0 && sk > 0) {
        fit.correlation[i][k] = (covariance[i][k] + range[i] * range[k] / 12) / (si * sk);
      }
    }
  }
}

// Where a state channel's noise estimate (its sixth differences) and its fourth differences
// disagree, the estimate holds signal the samples do not resolve: below a third of the sample
// rate the fourth difference weighs a signal at least 1.46 times as much as the sixth, and noise
// alike, which bounds the signal's share. The channel's noise then lies anywhere from the
// estimate less that share to the estimate: the equations are solved at the middle of that
// range, and the errors take the spread of the estimates over it. (A signal near 0.4 of the
// sample rate weighs the same in both and is not seen.) Records whose inputs are sampled only.
void allow_rough_noise(IdentifyResult& result, const LaggedChannels& channels,
                       const SolveOptions& solve_options, const std::vector<std::string>& names) {
  // Under inputs held over each sample the noise is estimated otherwise (held_lag_zero).
  if (result.data.hold != InputHold::kSample) return;
  std::vector<double> low = result.lagged->noise, middle = low;
  std::optional<IdentifyResult::Lagged::RoughNoise> rough;
  for (std::size_t c = 0; c < channels.states.size() && c < low.size(); ++c) {
    const std::optional<double>& sixth = result.data.channels[c].noise_variance;
    const std::optional<double> fourth = fourth_difference_noise(result.data.channels[c]);
    if (!sixth || !fourth || !(low[c] > 0) || low[c] != *sixth ||
        !(*fourth > IdentifyResult::Lagged::kRoughNoise * *sixth)) {
      continue;
    }
    const double share = std::min(1.0, (*fourth - *sixth) / (0.46 * *sixth));
    low[c] *= 1 - share;
    middle[c] *= 1 - share / 2;
    if (!rough || share > rough->share) rough = {channels.states[c], *sixth, *fourth, share, "", 0};
  }
  if (!rough) return;
  const auto solved = [&](const std::vector<double>& noise) {
    const LaggedRows rows = equations_of(result, *result.lagged->system, channels, noise);
    return solve_rows(rows.rows, names, result.data.estimates, solve_options);
  };
  const Estimate at_low = solved(low);
  Estimate at_middle = solved(middle);
  if (!at_low.usable() || !at_middle.usable()) return;
  const auto add_spread = [&](Fit& fit, const Fit& from, const Fit& to) {
    std::vector<double> range(fit.parameters.size(), 0.0);
    for (std::size_t p = 0; p < range.size(); ++p) {
      range[p] = to.parameters[p].estimate - from.parameters[p].estimate;
      const ParameterEstimate& e = fit.parameters[p];
      if (&fit != &at_middle.main() || e.fixed || !(e.std_error > 0)) continue;
      const double shift = std::abs(range[p]) / e.std_error;
      if (shift > rough->shift) rough->shift = shift, rough->parameter = e.name;
    }
    add_uniform_spread(fit, range);
  };
  add_spread(at_middle.least_squares, at_low.least_squares, result.estimate.least_squares);
  if (at_middle.optimal && at_low.optimal && result.estimate.optimal) {
    add_spread(*at_middle.optimal, *at_low.optimal, *result.estimate.optimal);
  }
  result.estimate = std::move(at_middle);
  result.lagged->noise = middle;
  result.lagged->rough_noise = rough;
}

// The noise on each channel and what the equations take from it and from the pass: the noise
// the formed states share with their columns, the stencils, the moments' accuracy floor.
void prepare_lagged(IdentifyResult& result, const LaggedChannels& channels,
                    const IdentifyOptions& options) {
  result.lagged->noise = noise_variances(result, channels, options);
  result.lagged->shared_noise = shared_noise(result, channels, result.lagged->noise);
  // The moments name the computed channels after the channels read (lagged_moment_text).
  result.lagged->channels.insert(result.lagged->channels.end(), channels.computed_names.begin(),
                                 channels.computed_names.end());
  // Inputs held over each sample put kinks into the states at the samples, which only the
  // five-point stencils match; band-limited records take the wide ones.
  result.lagged->stencil_reach =
      result.data.hold == InputHold::kSample ? kWideStencilReach : kStencilReach;
  result.lagged->moment_variance = accuracy_floor(
      result.lagged->moments, result.data.estimates.mean, noisy_channels(result, channels));
}

// The equations at the pass's moments with the noise `noise` on each channel (less the misfit
// taken out of them, Lagged::misfit), solved into result.estimate.
void solve_lagged(IdentifyResult& result, const LaggedPlan& plan, const LaggedChannels& channels,
                  const IdentifyOptions& options, const std::vector<double>& noise) {
  result.lagged->noise = noise;
  const LaggedRows rows = equations_of(result, *result.lagged->system, channels, noise);
  std::vector<std::string> names;
  for (const Declaration& p : result.model->parameters()) names.push_back(p.name);
  result.gmm = optimal_weighting(options, plan.fixed, rows.rows.a.size());
  const SolveOptions solve_options{.gmm = result.gmm,
                                   .fixed = plan.fixed,
                                   .normalise_rows = true,
                                   .iterate_weights = true,
                                   .moment_variance = result.lagged->moment_variance};
  result.estimate = solve_rows(rows.rows, names, result.data.estimates, solve_options);
  if (!options.noise && result.estimate.usable()) {
    allow_rough_noise(result, channels, solve_options, names);
  }
}

// Whether state `name` is formed from a column.
bool is_formed(const IdentifyResult::Integration& integration, const std::string& name) {
  return std::any_of(integration.formed.begin(), integration.formed.end(),
                     [&](const auto& f) { return f.state == name; });
}

// Whether the filter that forms states takes the function term `m` (over the model's variables)
// apart: a product with a formed state, or an abs or sign of one, which the pass computes from
// the filtered channels; not a product of measured states (LaggedChannels::products) or an abs
// or sign of measured channels, which it filters whole.
bool taken_apart(const Model& model, const LaggedChannels& channels,
                 const IdentifyResult::Integration& integration, const Monomial& m) {
  if (!channels.products.empty()) {
    Monomial read(channels.products.begin()->first.size(), 0);
    for (std::size_t u = 0; u < m.size(); ++u) {
      if (m[u] != 0) read[static_cast<std::size_t>(channels.channel[u])] = m[u];
    }
    if (channels.products.count(read)) return false;
  }
  const auto u = static_cast<std::size_t>(
      std::find_if(m.begin(), m.end(), [](int p) { return p != 0; }) - m.begin());
  if (u == m.size() || m.degree() != 1 || model.variables()[u].channel()) return true;
  const VariableFunction& f = model.function_of(model.variables()[u]);
  for (std::size_t s = 0; s < model.states().size(); ++s) {
    if (function_holds(f, s) && is_formed(integration, model.states()[s].name)) return true;
  }
  return false;
}

// The measured states that go through the filter forming states with every channel and that the
// equations hold nonlinearly with a formed state: what their terms lose is what the filter cuts.
std::vector<std::string> filtered_measured_states(const IdentifyResult& result,
                                                  const LaggedChannels& channels) {
  std::vector<std::string> out;
  if (!result.integration) return out;
  const Model& model = *result.model;
  const auto apart = [&](const Monomial& m) {
    return taken_apart(model, channels, *result.integration, m);
  };
  for (std::size_t v = 0; v < model.states().size(); ++v) {
    const std::string& name = model.states()[v].name;
    if (!is_formed(*result.integration, name) && channels.channel[v] >= 0 &&
        nonlinear_in(model, *result.lagged->system, v, apart)) {
      out.push_back(name);
    }
  }
  return out;
}

// Whether the filter forming states leaves a misfit in the equations: they hold a formed state,
// or a measured one with it, nonlinearly.
bool filter_leaves_misfit(const IdentifyResult& result, const LaggedChannels& channels) {
  if (!result.integration) return false;
  const auto& formed = result.integration->formed;
  return std::any_of(formed.begin(), formed.end(), [](const auto& f) { return f.cut; }) ||
         !filtered_measured_states(result, channels).empty();
}

// Takes the misfit that the filter forming states leaves out of the equations
// (IdentifyResult::Integration::Misfit) and solves them again, from the channels' noise
// `noise`. The equations of the response read the moments of the record's at the same lags and
// instruments, without noise; their residual at the estimates the response holds is the misfit.
void take_out_filter_misfit(IdentifyResult& result, const LaggedPlan& plan,
                            const LaggedChannels& channels, const DataSource& source,
                            const IdentifyOptions& options, const std::vector<double>& noise) {
  if (!result.estimate.usable()) return;
  // Assigned, not emplaced: clang takes a nested struct with member initialisers as not
  // default-constructible inside its enclosing class.
  result.integration->misfit = IdentifyResult::Integration::Misfit{};
  IdentifyResult::Integration::Misfit& misfit = *result.integration->misfit;
  if (options.input_shift != 0) {
    misfit.failure = "the response is not simulated under an input shift";
    return;
  }
  std::vector<double> residual;
  try {
    // The response's equations without noise: its derivative columns carry the recorded
    // inputs' noise, which drives it and is no sensor's (read as sensor noise, it moved k of a
    // hardening oscillator half a standard error the wrong way).
    const LaggedRows rows = lagged_rows(*result.lagged->system, *result.data.time_step,
                                        channels.channel, {}, result.lagged->stencil_reach,
                                        shared_noise(result, channels, {}), channels.products);
    residual = response_residual(result, rows, source, options,
                                 lagged_options(result, channels, result.estimate.rows, options),
                                 channels.states, channels.inputs, misfit);
    if (residual.empty()) return;
  } catch (const Interrupted&) {
    throw;
  } catch (const Error& e) {
    misfit.failure = e.what();
    return;
  }
  const Estimate before = result.estimate;
  result.lagged->misfit = std::move(residual);
  solve_lagged(result, plan, channels, options, noise);
  if (!result.estimate.usable()) {
    misfit.failure =
        "the equations without the misfit have no usable solution: " + result.estimate.message;
    result.estimate = before;
    result.lagged->misfit.clear();
    return;
  }
  const std::vector<ParameterEstimate>& after = result.parameters();
  const std::vector<ParameterEstimate>& was =
      before.optimal ? before.optimal->parameters : before.least_squares.parameters;
  for (std::size_t p = 0; p < after.size() && p < was.size(); ++p) {
    if (after[p].fixed || !(after[p].std_error > 0)) continue;
    const double shift = std::abs(after[p].estimate - was[p].estimate) / after[p].std_error;
    if (shift > misfit.shift) misfit.shift = shift, misfit.parameter = after[p].name;
  }
}

// The warnings of the lagged path: functions of noisy channels, states formed by integration
// whose misfit stayed in the equations.
void add_lagged_warnings(IdentifyResult& result, const LaggedChannels& channels) {
  const std::vector<std::string> noisy = noisy_function_warnings(result, channels);
  result.estimate.warnings.insert(result.estimate.warnings.end(), noisy.begin(), noisy.end());
  const auto& integration = result.integration;
  if (!integration || (integration->misfit && integration->misfit->failure.empty())) return;
  const std::string corner = number(integration->corner, "%.3g");
  const std::string why =
      integration->misfit
          ? " (its misfit could not be taken out: " + integration->misfit->failure + ")"
          : "";
  for (const std::string& name : filtered_measured_states(result, channels)) {
    result.estimate.warnings.push_back(
        "'" + name + "' goes through the high-pass at " + corner +
        " Hz with every channel, so that the equations of the states formed (--integrate) "
        "hold: the terms that hold it with a formed state lose the low frequencies the filter "
        "cuts, a bias the intervals do not include, and which the J test can see on a precise "
        "record" +
        why + " (docs/model-language.md, \"Forming a state from its acceleration\")");
  }
  for (const auto& formed : integration->formed) {
    if (!formed.cut) continue;
    result.estimate.warnings.push_back(
        "'" + formed.state + "' was formed from '" + formed.column + "' inside a high-pass at " +
        corner +
        " Hz: the terms nonlinear in it lose the low frequencies the filter cuts, a bias "
        "the intervals do not include, small where the force has no power below the corner" +
        why + " (docs/model-language.md, \"Forming a state from its acceleration\")");
  }
}

}  // namespace

void identify_lagged(IdentifyResult& result, const DataSource& source,
                     const IdentifyOptions& options, const std::vector<bool>& measured) {
  LaggedPlan plan = plan_lagged(*result.model, options, measured, result.integration);
  LaggedPass pass = read_lagged(result, plan, source, options);
  const std::string window_cut =
      options.lags ? "" : fit_window(result, plan, pass, source, options);
  if (!plan.instruments_cut.empty() || !window_cut.empty()) {
    result.lagged->cut = "cut to " + plan.instruments_cut +
                         (plan.instruments_cut.empty() || window_cut.empty() ? "" : " and ") +
                         window_cut + " to stay within " +
                         std::to_string(IdentifyOptions::kMaxLaggedMoments) + " moments";
  }
  if (result.integration) {
    for (auto& formed : result.integration->formed) {
      formed.cut =
          nonlinear_in(*result.model, *result.lagged->system,
                       static_cast<std::size_t>(result.model->variable_index(formed.state)));
    }
  }
  prepare_lagged(result, pass.channels, options);
  const std::vector<double> noise = result.lagged->noise;
  solve_lagged(result, plan, pass.channels, options, noise);
  if (filter_leaves_misfit(result, pass.channels)) {
    take_out_filter_misfit(result, plan, pass.channels, source, options, noise);
  }
  if (plan.check && pass.check_moments && result.estimate.j_pvalue) {
    check_with_zero_lag(result, *plan.check, *pass.check_moments, pass.channels.channel,
                        plan.fixed);
  }
  add_lagged_warnings(result, pass.channels);
}

}  // namespace momentid
