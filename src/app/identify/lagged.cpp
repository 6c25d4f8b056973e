// The lagged moment equations (docs/measured-data.md): an instrument at t - s times an
// equation at t, for records that lack a state's column or carry sensor noise.

#include <algorithm>
#include <cmath>
#include <tuple>

#include "app/identify/steps.hpp"

namespace momentid {
namespace {

// Per measured state that the lagged equations read: the lag at which its autocorrelation first
// falls below 1/e, from the lagged moments C[y;y](s) of the pass; 0 when it stays above across
// the window.
std::map<std::string, int> correlation_lags(const IdentifyResult& r,
                                            const std::vector<int>& channel) {
  const LaggedSystem& system = r.lagged->system;
  std::map<Moment, std::size_t> index;
  for (std::size_t k = 0; k < r.lagged->moments.size(); ++k) index.emplace(r.lagged->moments[k], k);
  std::map<std::string, int> out;
  for (std::size_t v = 0; v < r.model->states().size(); ++v) {
    if (channel[v] < 0 || !system.measured[v]) continue;
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
// window when a state stays correlated across it. Kept within the bounds of the lag options and
// of the number of moments identify takes.
int lag_window(const IdentifyResult& r) {
  const LaggedSystem& system = r.lagged->system;
  int wanted = 0;
  for (const auto& [name, tau] : r.lagged->correlation_lags) {
    wanted = std::max(wanted, tau > 0 ? 5 * tau : 4 * system.last_lag);
  }
  if (wanted == 0) return system.last_lag;
  // The moments grow with the number of lags.
  const double per_lag =
      static_cast<double>(r.lagged->moments.size()) / (system.last_lag - system.first_lag + 1);
  const int most = system.first_lag - 1 +
                   static_cast<int>(IdentifyOptions::kMaxLaggedMoments / std::max(per_lag, 1.0));
  return std::clamp(std::min(wanted, most), system.first_lag + LagOptions::kMinSpan - 1,
                    LagOptions::kMaxLag);
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
      if (!measured[v]) missing += (missing.empty() ? "" : ", ") + model.variables()[v];
    }
    throw UsageError(
        "multipliers and a degree choose zero-lag equations, but " +
        (options.lags ? std::string("lags were asked for") : "the data lack " + missing) +
        ": the lagged equations take instruments instead");
  }
}

// The channels a lagged pass reads: the variables the equations need, states then inputs, as
// the accumulator numbers them.
struct LaggedChannels {
  std::vector<std::string> states, inputs;
  std::vector<int> channel;  // per model variable: its channel, or -1 when not read
};

LaggedChannels lagged_channels(const Model& model, const LaggedSystem& system) {
  LaggedChannels out;
  const std::size_t state_count = model.states().size();
  out.channel.assign(model.variables().size(), -1);
  for (std::size_t v = 0, next = 0; v < model.variables().size(); ++v) {
    if (!system.needed[v]) continue;
    (v < state_count ? out.states : out.inputs).push_back(model.variables()[v]);
    // States come first among the channels, and the variables are in that order too.
    out.channel[v] = static_cast<int>(next++);
  }
  return out;
}

// Derives the equations for the lags of `lag_options` and makes the pass over the data into
// `result`.
LaggedChannels read_lagged(IdentifyResult& result, const LagOptions& lag_options,
                           const DataSource& source, const IdentifyOptions& options) {
  result.lagged.emplace().system = derive_lagged(*result.model, lag_options);
  LaggedChannels c = lagged_channels(*result.model, result.lagged->system);
  result.lagged->channels = c.states;
  result.lagged->channels.insert(result.lagged->channels.end(), c.inputs.begin(), c.inputs.end());
  // The rows need the sample interval, which the data give: accumulate, then build rows.
  const LaggedRows probe = lagged_rows(result.lagged->system, 1.0, c.channel, {});
  if (probe.moments.size() > IdentifyOptions::kMaxLaggedMoments) {
    throw UsageError("lags " + std::to_string(result.lagged->system.first_lag) + ".." +
                     std::to_string(result.lagged->system.last_lag) + " with " +
                     std::to_string(result.lagged->system.instruments.size()) +
                     " instruments need " + std::to_string(probe.moments.size()) +
                     " moments, more than " + std::to_string(IdentifyOptions::kMaxLaggedMoments) +
                     ": use fewer lags or instruments");
  }
  result.lagged->moments = probe.moments;
  DataOptions data_options = pass_options(options);
  // The optimal weighting estimates the equations' covariance from the batches.
  data_options.min_batches = kBatchesPerEquation * probe.rows.a.size();
  data_options.offsets =
      channel_offsets(source, c.states, c.inputs, data_options, options.center, result.centered);
  result.data = moments_from_data(source, c.states, c.inputs, probe.moments, data_options);
  if (!result.data.time_step) {
    throw DataError({source.name(), 1, 1, ""},
                    "the lagged equations need the sample interval: give the data a 't' "
                    "column or a dt in the metadata");
  }
  result.lagged->correlation_lags = correlation_lags(result, c.channel);
  return c;
}

// The noise on each state channel: given, or estimated from its autocorrelation (inputs are
// taken as measured without noise).
std::vector<double> noise_variances(const IdentifyResult& result, std::size_t states,
                                    const IdentifyOptions& options) {
  std::vector<double> noise(result.lagged->channels.size(), 0.0);
  for (std::size_t c = 0; c < states; ++c) {
    if (options.noise) {
      const auto given = options.noise->find(result.lagged->channels[c]);
      if (given != options.noise->end()) noise[c] = given->second;
    } else if (const auto& v = result.data.channels[c].noise_variance) {
      noise[c] = std::max(0.0, *v);
    }
  }
  return noise;
}

}  // namespace

void identify_lagged(IdentifyResult& result, const DataSource& source,
                     const IdentifyOptions& options, const std::vector<bool>& measured) {
  const Model& model = *result.model;
  check_lagged_options(model, options, measured);
  LagOptions lag_options;
  if (options.lags) std::tie(lag_options.first_lag, lag_options.last_lag) = *options.lags;
  lag_options.instruments = options.instruments;
  lag_options.measured = measured;
  LaggedChannels channels = read_lagged(result, lag_options, source, options);
  // The default lags span about five correlation times of the measured states: when the
  // first pass shows them far from that (more than 1.5 times longer or 2 times shorter), a
  // second pass takes the lags the data call for.
  if (!options.lags) {
    const int wanted = lag_window(result);
    const int last = result.lagged->system.last_lag;
    if (2 * wanted > 3 * last || 2 * wanted < last) {
      lag_options.last_lag = wanted;
      channels = read_lagged(result, lag_options, source, options);
    }
  }
  result.lagged->noise = noise_variances(result, channels.states.size(), options);
  // Inputs held over each sample put kinks into the states at the samples, which only the
  // five-point stencils match; band-limited records take the wide ones.
  result.lagged->stencil_reach =
      result.data.hold == InputHold::kSample ? kWideStencilReach : kStencilReach;
  const LaggedRows rows =
      lagged_rows(result.lagged->system, *result.data.time_step, channels.channel,
                  result.lagged->noise, result.lagged->stencil_reach);
  std::vector<std::string> names;
  for (const Declaration& p : model.parameters()) names.push_back(p.name);
  result.gmm = options.gmm.value_or(true);
  result.estimate = solve_rows(
      rows.rows, names, result.data.estimates,
      {.gmm = result.gmm, .fixed = fixed_values(model, options.fixed), .normalise_rows = true});
}

}  // namespace momentid
