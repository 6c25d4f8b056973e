#include "momentid/identify.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "app/variables.hpp"
#include "common/json.hpp"
#include "solve/long_run.hpp"

namespace momentid {
namespace {

// Sensor noise above this fraction of a state's standard deviation is reported. Below it the
// estimate cannot tell noise from the roughness of a state whose derivative holds a held input.
constexpr double kNoiseWarning = 0.02;

// Four batches per equation keep the optimal weighting's batch covariance well conditioned.
constexpr std::size_t kBatchesPerEquation = 4;

// What makes a result doubtful, and what draws a warning (README, "Warnings").
constexpr double kIdentityZ = 4;      // |z| of a stationarity identity's violation
constexpr double kJRejection = 0.01;  // p-value of the J test
constexpr double kOffset = 0.2;       // |mean| / standard deviation of a channel
constexpr double kWeakRelativeError = 0.1;
constexpr double kStrongCorrelation = 0.95;

}  // namespace

void IdentifyOptions::validate(const Model& model) const {
  if (batches && (*batches < kMinBatches || *batches > kMaxBatches)) {
    throw UsageError("batches: expected a number from " + std::to_string(kMinBatches) + " to " +
                     std::to_string(kMaxBatches) + ", found " + std::to_string(*batches));
  }
  if (degree < 0 || degree > kMaxDegree) {
    throw UsageError("degree: expected 0 (automatic) or a number from 1 to " +
                     std::to_string(kMaxDegree) + ", found " + std::to_string(degree));
  }
  if (input_shift < -kMaxInputShift || input_shift > kMaxInputShift) {
    throw UsageError("input shift: expected a number from -" + std::to_string(kMaxInputShift) +
                     " to " + std::to_string(kMaxInputShift) + ", found " +
                     std::to_string(input_shift));
  }
  const auto& variables = model.variables();
  for (const auto& [name, value] : fixed) {
    if (model.parameter_index(name) < 0) {
      throw UsageError("--fix: '" + name + "' is not a parameter of model " + model.name());
    }
    if (!std::isfinite(value)) {
      throw UsageError("--fix: the value of '" + name + "' must be a finite number");
    }
  }
  const auto declared_fixed = [&](const Declaration& p) { return p.fixed || fixed.count(p.name); };
  if (!model.parameters().empty() &&
      std::all_of(model.parameters().begin(), model.parameters().end(), declared_fixed)) {
    throw UsageError("--fix: every parameter of model " + model.name() +
                     " is fixed (by --fix or in the model file): there is nothing to estimate");
  }
  for (const std::string& name : center) {
    if (std::find(variables.begin(), variables.end(), name) == variables.end()) {
      throw UsageError("--center: '" + name + "' is not a state or input of model " + model.name());
    }
  }
  if (dt && !(std::isfinite(*dt) && *dt > 0)) {
    throw UsageError("--dt: expected a positive number");
  }
  for (const auto& column : columns) {
    if (column.first == "t") continue;
    if (std::find(variables.begin(), variables.end(), column.first) == variables.end()) {
      throw UsageError("--columns: '" + column.first + "' is not a state or input of model " +
                       model.name());
    }
  }
}

const std::vector<ParameterEstimate>& IdentifyResult::parameters() const {
  return gmm && !estimate.gmm_parameters.empty() ? estimate.gmm_parameters : estimate.parameters;
}

namespace {

// Per measured state that the lagged equations read: the lag at which its autocorrelation first
// falls below 1/e, from the lagged moments C[y;y](s) of the pass; 0 when it stays above across
// the window.
std::map<std::string, int> correlation_lags(const IdentifyResult& r,
                                            const std::vector<int>& channel) {
  const LaggedSystem& system = *r.lagged;
  std::map<Moment, std::size_t> index;
  for (std::size_t k = 0; k < r.lagged_moments.size(); ++k) index.emplace(r.lagged_moments[k], k);
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
  const LaggedSystem& system = *r.lagged;
  int wanted = 0;
  for (const auto& [name, tau] : r.correlation_lags) {
    wanted = std::max(wanted, tau > 0 ? 5 * tau : 4 * system.last_lag);
  }
  if (wanted == 0) return system.last_lag;
  // The moments grow with the number of lags.
  const double per_lag =
      static_cast<double>(r.lagged_moments.size()) / (system.last_lag - system.first_lag + 1);
  const int most = system.first_lag - 1 +
                   static_cast<int>(IdentifyOptions::kMaxLaggedMoments / std::max(per_lag, 1.0));
  return std::clamp(std::min(wanted, most), system.first_lag + LagOptions::kMinSpan - 1,
                    LagOptions::kMaxLag);
}

// The offsets of DataOptions for the channels `states` then `inputs`: the mean of each channel
// that `center` names, from a pass of its own, and 0 for the others; none when `center` names
// none of them. Records the means removed in `centered`.
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

// The parameters fixed by IdentifyOptions::fixed or in the model file (the option's value wins),
// as SolveOptions::fixed wants them: per parameter, in declaration order.
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

// The moments the pass reads for `moments` (over the model's variables): a rate of change
// (rate_key) as the increment of its monomial.
std::vector<Moment> pass_moments_of(const Model& model, const std::vector<Monomial>& moments) {
  std::vector<Moment> out;
  for (const Monomial& m : moments) {
    const std::optional<Monomial> g = rate_of(m, model.variables().size());
    out.push_back(g ? Moment::increment_of(*g) : Moment::from_monomial(m));
  }
  return out;
}

// `moments` without the rates of change.
std::vector<Monomial> without_rates(const Model& model, std::vector<Monomial> moments) {
  std::erase_if(moments, [&](const Monomial& m) { return rate_of(m, model.variables().size()); });
  return moments;
}

// Turns the averages of the increments among `moments` (pass_moments_of) into the record's rates
// of change, dividing by the interval `interval` between the rows the pass read; without it, sets
// them to 0 (their stationary value) in every batch.
void increments_to_rates(const Model& model, const std::vector<Monomial>& moments,
                         std::optional<double> interval, MomentEstimates& estimates) {
  for (std::size_t k = 0; k < moments.size(); ++k) {
    if (!rate_of(moments[k], model.variables().size())) continue;
    const double scale = interval ? 1 / *interval : 0.0;
    estimates.mean[k] *= scale;
    for (std::vector<double>& batch : estimates.batch_means) batch[k] *= scale;
  }
}

// The monomials g of the rates of change E[(g)'] among `moments`, in their order.
std::vector<Monomial> rate_monomials(const Model& model, const std::vector<Monomial>& moments) {
  std::vector<Monomial> out;
  for (const Monomial& m : moments) {
    if (const std::optional<Monomial> g = rate_of(m, model.variables().size())) out.push_back(*g);
  }
  return out;
}

// The products g_i * g_j of the monomials `g` (i <= j), with the g themselves.
std::vector<Monomial> with_products(const std::vector<Monomial>& g) {
  std::vector<Monomial> out = g;
  for (std::size_t i = 0; i < g.size(); ++i) {
    for (std::size_t j = i; j < g.size(); ++j) {
      Monomial product = g[i];
      for (std::size_t v = 0; v < product.size(); ++v) product[v] += g[j][v];
      out.push_back(std::move(product));
    }
  }
  return out;
}

// The covariance of the record's rates of change (g(end) - g(start)) / T summed over its runs,
// for the monomials `g` whose moments and products (with_products) are among `moments` with
// `estimates`: each run's ends, far apart, are independent draws of the stationary states, so
// that the covariance is 2 runs Cov(g_i, g_j) / T^2 (README, "Uncertainty").
std::vector<std::vector<double>> rate_covariance(const std::vector<Monomial>& g,
                                                 const std::vector<Monomial>& moments,
                                                 const MomentEstimates& estimates, std::size_t runs,
                                                 double duration) {
  std::map<Monomial, double> mean;
  for (std::size_t k = 0; k < moments.size(); ++k) mean.emplace(moments[k], estimates.mean[k]);
  const std::vector<Monomial> all = with_products(g);
  std::vector<std::vector<double>> out(g.size(), std::vector<double>(g.size()));
  for (std::size_t i = 0, next = g.size(); i < g.size(); ++i) {
    for (std::size_t j = i; j < g.size(); ++j, ++next) {
      const double c = mean.at(all[next]) - mean.at(g[i]) * mean.at(g[j]);
      out[i][j] = out[j][i] = 2 * static_cast<double>(runs) * c / (duration * duration);
    }
  }
  return out;
}

// IdentifyOptions::extrapolate, after the zero-lag estimate `result` whose first-order errors
// over the batches are `fine_errors`: the same estimate from every other sample (both halves of
// each run, in the same batches), the difference's error from the long-run covariance of the
// difference of the two error series, and Richardson's extrapolation when a difference exceeds
// its error.
void estimate_sampling_bias(IdentifyResult& result, const DataSource& source,
                            const std::vector<std::string>& states,
                            const std::vector<std::string>& inputs, DataOptions data_options,
                            const IdentifyOptions& options,
                            const std::vector<std::vector<double>>& fine_errors) {
  if (!inputs.empty() && result.data.hold == InputHold::kZeroOrderHold) {
    throw UsageError(
        "extrapolate: the input is held over each sample (input hold zoh): every other sample "
        "of such a record is not the record sampled at 2 dt, whose input would be held over "
        "2 dt; the kinks of the held input are corrected from the model instead");
  }
  Estimate& fine = result.estimate;
  if (fine_errors.empty() || fine.status != Estimate::Status::kOk) return;
  data_options.stride = 2;
  data_options.hold = result.data.hold;
  // The same batches: the accumulator keeps as many stretches, each of half as many intervals
  // (every other sample), so that they cover the same times as the record's, and the same
  // count of them make a batch.
  if (data_options.batches == 0) {
    data_options.min_batches = std::max(data_options.min_batches, fine.batches);
  }
  MomentEstimates coarse;
  for (std::size_t phase = 0; phase < 2; ++phase) {
    data_options.phase = phase;
    DataMoments pass = moments_from_data(
        source, states, inputs, pass_moments_of(*result.model, result.moments), data_options);
    MomentEstimates& half = pass.estimates;
    increments_to_rates(*result.model, result.moments, pass.time_step, half);  // at 2 dt
    if (half.batch_means.size() != fine.batches) {
      throw Error(source.name() + ": every other sample gives " +
                  std::to_string(half.batch_means.size()) + " batches, not " +
                  std::to_string(fine.batches) +
                  ": too short a record for the sampling bias (use --batches)");
    }
    if (phase == 0) {
      coarse = half;
      continue;
    }
    for (std::size_t k = 0; k < coarse.mean.size(); ++k) {
      coarse.mean[k] = (coarse.mean[k] + half.mean[k]) / 2;
      for (std::size_t b = 0; b < fine.batches; ++b) {
        coarse.batch_means[b][k] = (coarse.batch_means[b][k] + half.batch_means[b][k]) / 2;
      }
    }
    for (std::size_t b = 0; b < fine.batches; ++b) {
      coarse.batch_intervals[b] += half.batch_intervals[b];
    }
    coarse.intervals += half.intervals;
  }
  const Estimate c =
      solve(result.system, result.moments, coarse,
            {.gmm = result.gmm, .fixed = fixed_values(*result.model, options.fixed)});
  const std::vector<std::vector<double>>& coarse_errors = c.error_batches;
  const bool gmm = result.gmm && !fine.gmm_parameters.empty();
  std::vector<ParameterEstimate>& list = gmm ? fine.gmm_parameters : fine.parameters;
  const std::vector<ParameterEstimate>& coarse_list =
      gmm && !c.gmm_parameters.empty() ? c.gmm_parameters : c.parameters;
  if (c.status != Estimate::Status::kOk || coarse_errors.size() != fine_errors.size() ||
      coarse_list.size() != list.size()) {
    fine.warnings.push_back("no sampling bias: every other sample does not give an estimate");
    return;
  }
  // theta(h) = theta(0) + C h^p: the bias at dt is (theta(2 dt) - theta(dt)) / (2^p - 1).
  const double r = 1 / (std::pow(2.0, IdentifyResult::SamplingBias::kOrder) - 1);
  const auto batches = static_cast<Eigen::Index>(fine_errors.size());
  const auto params = static_cast<Eigen::Index>(list.size());
  Eigen::MatrixXd difference(batches, params), extrapolated(batches, params);
  for (Eigen::Index b = 0; b < batches; ++b) {
    for (Eigen::Index p = 0; p < params; ++p) {
      const double f = fine_errors[static_cast<std::size_t>(b)][static_cast<std::size_t>(p)];
      const double g = coarse_errors[static_cast<std::size_t>(b)][static_cast<std::size_t>(p)];
      difference(b, p) = f - g;
      extrapolated(b, p) = f + r * (f - g);
    }
  }
  const LongRunCovariance difference_errors = long_run_covariance(difference);
  IdentifyResult::SamplingBias bias;
  for (Eigen::Index p = 0; p < params; ++p) {
    const auto i = static_cast<std::size_t>(p);
    const double error = std::sqrt(difference_errors.covariance(p, p));
    bias.coarse.push_back(coarse_list[i].estimate);
    bias.bias.push_back(r * (coarse_list[i].estimate - list[i].estimate));
    bias.difference_error.push_back(error);
    bias.applied = bias.applied || (!list[i].fixed && list[i].identifiable &&
                                    std::abs(list[i].estimate - coarse_list[i].estimate) > error);
  }
  if (bias.applied) {
    const LongRunCovariance errors = long_run_covariance(extrapolated);
    const double t975 = errors.t975();
    for (Eigen::Index p = 0; p < params; ++p) {
      ParameterEstimate& e = list[static_cast<std::size_t>(p)];
      if (e.fixed) continue;
      e.estimate -= bias.bias[static_cast<std::size_t>(p)];
      e.std_error = std::sqrt(errors.covariance(p, p));
      e.ci_low = e.estimate - t975 * e.std_error;
      e.ci_high = e.estimate + t975 * e.std_error;
    }
    (gmm ? fine.gmm_dof : fine.dof) = errors.dof;
  }
  result.sampling_bias = std::move(bias);
}

// The first `count` moments of `all`, overall and per batch.
MomentEstimates first_moments(const MomentEstimates& all, std::size_t count) {
  MomentEstimates out = all;
  out.mean.resize(count);
  for (std::vector<double>& batch : out.batch_means) batch.resize(count);
  return out;
}

// Those of `more` that are neither among `moments` nor the constant 1, each once, in their order.
std::vector<Monomial> not_among(const std::vector<Monomial>& moments,
                                const std::vector<Monomial>& more) {
  std::set<Monomial> known(moments.begin(), moments.end());
  std::vector<Monomial> out;
  for (const Monomial& m : more) {
    const bool constant = std::all_of(m.begin(), m.end(), [](int e) { return e == 0; });
    if (!constant && known.insert(m).second) out.push_back(m);
  }
  return out;
}

// The moments the E[g''] of `held` are made of.
std::vector<Monomial> second_derivative_moments(const HeldInputCorrections& held) {
  std::vector<Monomial> out;
  for (const HeldInputCorrection& c : held.moments) {
    for (const auto& [m, weight] : c.second_derivative) out.push_back(m);
  }
  return out;
}

// Data whose input is held over each sample: replaces the estimate of `result` by the one from
// moments corrected for the kinks of the held input, E[g] = E_dt[g] - dt^2/12 E[g''] (derive.hpp,
// held_input_corrections), with the weights of E[g''] at the parameters of the previous
// estimate, twice (the second pass changes the estimates by O(dt^4)). `all` holds the moments
// `moments` in that order, the system's first.
void correct_for_held_input(IdentifyResult& result, const HeldInputCorrections& held,
                            const std::vector<Monomial>& moments, const MomentEstimates& all,
                            const SolveOptions& solve_options) {
  if (held.moments.empty() && held.unavailable.empty()) return;  // no moment needs it
  IdentifyResult::HeldInput& out = result.held_input.emplace();
  if (held.moments.empty()) {
    out.unavailable = held.unavailable;
    return;
  }
  if (!result.data.time_step) {
    out.unavailable = "the data give no sample interval (a 't' column or a dt in the metadata)";
    return;
  }
  std::map<Monomial, std::size_t> index;
  for (std::size_t k = 0; k < moments.size(); ++k) index.emplace(moments[k], k);
  const Model& model = *result.model;
  const double scale = *result.data.time_step * *result.data.time_step / 12;
  std::vector<double> before;
  for (const ParameterEstimate& p : result.parameters()) before.push_back(p.estimate);
  // Where a round cannot be made, the result is the uncorrected one.
  const Estimate uncorrected = result.estimate;
  const MomentEstimates uncorrected_moments = result.data.estimates;
  const auto give_up = [&](const char* reason) {
    out.unavailable = reason;
    result.estimate = uncorrected;
    result.data.estimates = uncorrected_moments;
  };
  std::vector<double> theta = before;
  for (int round = 0; round < 2; ++round) {
    if (result.estimate.status != Estimate::Status::kOk ||
        std::any_of(theta.begin(), theta.end(), [](double t) { return !std::isfinite(t); })) {
      return give_up("the estimate without it does not determine every parameter");
    }
    GiNaC::exmap values;
    for (std::size_t p = 0; p < theta.size(); ++p) {
      values[model.parameter_symbol(static_cast<int>(p))] = theta[p];
    }
    MomentEstimates corrected = first_moments(all, result.moments.size());
    for (const HeldInputCorrection& c : held.moments) {
      const std::size_t target = index.at(c.moment);
      for (const auto& [m, weight] : c.second_derivative) {
        double w = std::numeric_limits<double>::quiet_NaN();
        try {
          const GiNaC::ex value = weight.subs(values).evalf();
          if (GiNaC::is_a<GiNaC::numeric>(value)) {
            w = scale * GiNaC::ex_to<GiNaC::numeric>(value).to_double();
          }
        } catch (const std::exception&) {  // e.g. a division by a parameter estimated as 0
        }
        if (!std::isfinite(w)) {
          return give_up("its weights cannot be evaluated at the estimated parameters");
        }
        const auto source = index.find(m);
        if (source == index.end()) {  // the constant 1
          corrected.mean[target] -= w;
          for (std::vector<double>& batch : corrected.batch_means) batch[target] -= w;
          continue;
        }
        corrected.mean[target] -= w * all.mean[source->second];
        for (std::size_t b = 0; b < corrected.batch_means.size(); ++b) {
          corrected.batch_means[b][target] -= w * all.batch_means[b][source->second];
        }
      }
    }
    result.estimate = solve(result.system, result.moments, corrected, solve_options);
    result.data.estimates = std::move(corrected);
    theta.clear();
    for (const ParameterEstimate& p : result.parameters()) theta.push_back(p.estimate);
  }
  for (std::size_t p = 0; p < theta.size(); ++p) out.shift.push_back(theta[p] - before[p]);
}

}  // namespace

IdentifyResult identify(const Model& model, const DataSource& source,
                        const IdentifyOptions& options) {
  options.validate(model);
  IdentifyResult result;
  result.model = std::make_shared<const Model>(model);
  result.data_name = source.name();
  DataOptions data_options;
  data_options.hold = options.hold;
  data_options.batches = options.batches.value_or(0);
  data_options.rename = options.columns;
  data_options.min_rows = 2 * (options.batches ? *options.batches : DataOptions::kMinAutoBatches);
  data_options.input_shift = options.input_shift;
  data_options.dt = options.dt;
  data_options.layout = options.layout;
  data_options.control = options.control;
  data_options.lags = 4;  // for the noise estimates

  // Which variables the data have: the lagged equations serve data without some state.
  const std::vector<bool> measured =
      variables_present(model, source, options.columns, options.layout);
  const bool all_measured = std::all_of(measured.begin(), measured.end(), [](bool m) { return m; });
  // Without lags asked for, data that cannot show a state (not even as a derivative) get the
  // zero-lag pass and its message naming the missing column.
  if (!options.lags && (all_measured || !derivable_from(model, measured))) {
    DeriveOptions derive_options;
    derive_options.multipliers = options.multipliers;
    derive_options.degree = options.degree;
    derive_options.rates = true;
    result.system = derive(*result.model, derive_options);
    result.moments = moments_to_estimate(result.system);
    std::vector<std::string> states, inputs;
    for (const auto& d : model.states()) states.push_back(d.name);
    for (const auto& d : model.inputs()) inputs.push_back(d.name);
    result.gmm = options.gmm.value_or(false);
    // The optimal weighting estimates the equations' covariance from the batches.
    if (result.gmm) data_options.min_batches = kBatchesPerEquation * result.system.equations.size();
    data_options.offsets =
        channel_offsets(source, states, inputs, data_options, options.center, result.centered);
    // A held input puts kinks into the states at the samples: the moments whose derivative
    // holds it are then corrected, with E[g''] from moments the pass adds (unless the data are
    // known to be sampled).
    const HeldInputCorrections held =
        !inputs.empty() && options.hold != InputHold::kSample
            ? held_input_corrections(model, without_rates(model, result.moments))
            : HeldInputCorrections{};
    // The ends of the record: the rates of change, with the products their covariance needs,
    // unless these would more than double the pass.
    const std::vector<Monomial> rated = rate_monomials(model, result.moments);
    std::vector<Monomial> pass_moments = result.moments;
    const std::vector<Monomial> kinks = not_among(pass_moments, second_derivative_moments(held));
    pass_moments.insert(pass_moments.end(), kinks.begin(), kinks.end());
    const std::vector<Monomial> products = not_among(pass_moments, with_products(rated));
    std::string ends_unavailable;
    if (products.size() > pass_moments.size()) {
      ends_unavailable = "their covariance would need " + std::to_string(products.size()) +
                         " more moments than the " + std::to_string(pass_moments.size()) +
                         " the pass reads (the products of " + std::to_string(rated.size()) +
                         " rates of change)";
    } else {
      pass_moments.insert(pass_moments.end(), products.begin(), products.end());
    }
    // The correction removes the trapezoidal rule's error on the held products too, which the
    // cubic rule only makes smaller.
    if (!held.moments.empty()) data_options.held_rule = HeldRule::kTrapezoidal;
    result.data = moments_from_data(source, states, inputs, pass_moments_of(model, pass_moments),
                                    data_options);
    if (result.data.hold == InputHold::kZeroOrderHold && !held.moments.empty() &&
        !result.data.time_step) {
      // No correction without the sample interval: the cubic rule then does better.
      data_options.held_rule = HeldRule::kCubic;
      result.data = moments_from_data(source, states, inputs, pass_moments_of(model, pass_moments),
                                      data_options);
    }
    if (!result.data.time_step && ends_unavailable.empty()) {
      ends_unavailable = "the data give no sample interval (a 't' column or a dt in the metadata)";
    }
    // Without their covariance the rates stay out of the batches, whose series then holds the
    // ends.
    increments_to_rates(model, pass_moments,
                        ends_unavailable.empty() ? result.data.time_step : std::nullopt,
                        result.data.estimates);
    const MomentEstimates all = std::move(result.data.estimates);
    result.data.estimates = first_moments(all, result.moments.size());
    SolveOptions solve_options{.gmm = result.gmm, .fixed = fixed_values(model, options.fixed)};
    if (!rated.empty()) {
      result.end_values.emplace().unavailable = ends_unavailable;
      if (ends_unavailable.empty() && result.data.estimates.intervals > 0) {
        solve_options.rate_covariance = rate_covariance(
            rated, pass_moments, all, std::max<std::size_t>(result.data.runs, 1),
            static_cast<double>(result.data.estimates.intervals) * *result.data.time_step);
      }
    }
    result.estimate = solve(result.system, result.moments, result.data.estimates, solve_options);
    const std::vector<std::vector<double>> errors = result.estimate.error_batches;
    if (result.data.hold == InputHold::kZeroOrderHold) {
      correct_for_held_input(result, held, pass_moments, all, solve_options);
    }
    if (options.extrapolate) {
      estimate_sampling_bias(result, source, states, inputs, data_options, options, errors);
    }
    return result;
  }

  if (options.extrapolate) {
    throw UsageError(
        "extrapolate: the sampling bias is estimated for the zero-lag equations, and these data "
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
  LagOptions lag_options;
  if (options.lags) std::tie(lag_options.first_lag, lag_options.last_lag) = *options.lags;
  lag_options.instruments = options.instruments;
  lag_options.measured = measured;
  // The channels the equations read, states then inputs, as the accumulator numbers them.
  std::vector<std::string> states, inputs;
  std::vector<int> channel(model.variables().size(), -1);
  // Derives the equations for the lags of lag_options and makes the pass over the data.
  const auto pass = [&] {
    result.lagged = derive_lagged(*result.model, lag_options);
    states.clear();
    inputs.clear();
    const std::size_t state_count = model.states().size();
    for (std::size_t v = 0; v < model.variables().size(); ++v) {
      if (result.lagged->needed[v])
        (v < state_count ? states : inputs).push_back(model.variables()[v]);
    }
    for (std::size_t v = 0, next = 0; v < model.variables().size(); ++v) {
      // States come first among the channels, and the variables are in that order too.
      channel[v] = result.lagged->needed[v] ? static_cast<int>(next++) : -1;
    }
    result.channels = states;
    result.channels.insert(result.channels.end(), inputs.begin(), inputs.end());
    // The rows need the sample interval, which the data give: accumulate, then build rows.
    const LaggedRows probe = lagged_rows(*result.lagged, 1.0, channel, {});
    if (probe.moments.size() > IdentifyOptions::kMaxLaggedMoments) {
      throw UsageError("lags " + std::to_string(result.lagged->first_lag) + ".." +
                       std::to_string(result.lagged->last_lag) + " with " +
                       std::to_string(result.lagged->instruments.size()) + " instruments need " +
                       std::to_string(probe.moments.size()) + " moments, more than " +
                       std::to_string(IdentifyOptions::kMaxLaggedMoments) +
                       ": use fewer lags or instruments");
    }
    result.lagged_moments = probe.moments;
    // The optimal weighting estimates the equations' covariance from the batches.
    data_options.min_batches = kBatchesPerEquation * probe.rows.a.size();
    data_options.offsets =
        channel_offsets(source, states, inputs, data_options, options.center, result.centered);
    result.data = moments_from_data(source, states, inputs, probe.moments, data_options);
    if (!result.data.time_step) {
      throw DataError({source.name(), 1, 1, ""},
                      "the lagged equations need the sample interval: give the data a 't' "
                      "column or a dt in the metadata");
    }
    result.correlation_lags = correlation_lags(result, channel);
  };
  pass();
  // The default lags span about five correlation times of the measured states: when the
  // first pass shows them far from that (more than 1.5 times longer or 2 times shorter), a
  // second pass takes the lags the data call for.
  if (!options.lags) {
    const int wanted = lag_window(result);
    const int last = result.lagged->last_lag;
    if (2 * wanted > 3 * last || 2 * wanted < last) {
      lag_options.last_lag = wanted;
      pass();
    }
  }
  // The noise on each state channel: given, or estimated from its autocorrelation (inputs are
  // taken as measured without noise).
  result.noise.assign(result.channels.size(), 0.0);
  for (std::size_t c = 0; c < states.size(); ++c) {
    if (options.noise) {
      const auto given = options.noise->find(states[c]);
      if (given != options.noise->end()) result.noise[c] = given->second;
    } else if (const auto& v = result.data.channels[c].noise_variance) {
      result.noise[c] = std::max(0.0, *v);
    }
  }
  // Inputs held over each sample put kinks into the states at the samples, which only the
  // five-point stencils match; band-limited records take the wide ones.
  result.stencil_reach = result.data.hold == InputHold::kSample ? kWideStencilReach : kStencilReach;
  const LaggedRows rows = lagged_rows(*result.lagged, *result.data.time_step, channel, result.noise,
                                      result.stencil_reach);
  std::vector<std::string> names;
  for (const Declaration& p : model.parameters()) names.push_back(p.name);
  result.gmm = options.gmm.value_or(true);
  result.estimate = solve_rows(
      rows.rows, names, result.data.estimates,
      {.gmm = result.gmm, .fixed = fixed_values(model, options.fixed), .normalise_rows = true});
  return result;
}

namespace {

// Whether every term of every equation has an odd degree, counting a derivative as a factor:
// then the model is unchanged when every state and input changes sign, and zero-mean inputs
// give zero-mean states.
bool symmetric(const Model& model) {
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      int degree = t.derivative >= 0 ? 1 : 0;
      for (int e : t.monomial) degree += e;
      if (degree % 2 == 0) return false;
    }
  }
  return true;
}

std::string figure(double x, const char* format = "%.2g") {
  char text[32];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

}  // namespace

std::vector<std::string> doubts(const IdentifyResult& r) {
  std::vector<std::string> out;
  const Estimate& e = r.estimate;
  if (e.j_pvalue && *e.j_pvalue < kJRejection && r.gmm) {
    out.push_back("the J test rejects the model (p = " + figure(*e.j_pvalue) +
                  "): its moment equations disagree with each other more than their errors "
                  "allow. A term may be missing, a noise or an offset not modelled, or the "
                  "record too coarsely sampled: check the estimates with 'momentid validate' "
                  "before using them");
  }
  for (const IdentityCheck& c : e.identities) {
    if (!(std::abs(c.z) > kIdentityZ)) continue;
    out.push_back("the stationarity identity " + c.identity +
                  " is violated (z = " + figure(c.z, "%.3g") +
                  "): the record is not stationary (a drift, a start-up transient, runs joined "
                  "end to end), or its columns are not what the model's kinematic equations say "
                  "(v is not y', or the channels are shifted in time)");
  }
  if (symmetric(*r.model)) {
    const auto offset = [](const ChannelStatistics& c) {
      return c.variance > 0 && std::abs(c.mean) > kOffset * std::sqrt(c.variance);
    };
    const auto& channels = r.data.channels;
    const bool inputs_centred = std::none_of(
        channels.begin(), channels.end(), [&](const auto& c) { return c.is_input && offset(c); });
    for (const ChannelStatistics& c : channels) {
      if (c.is_input || !inputs_centred || !offset(c)) continue;
      out.push_back("'" + c.name + "' has the mean " + figure(c.mean, "%.3g") + ", " +
                    figure(std::abs(c.mean) / std::sqrt(c.variance)) +
                    " of its standard deviation, but model " + r.model->name() +
                    " is symmetric (every term odd) and its inputs have no mean, so its states "
                    "have none: a sensor offset? It biases the estimates; if it is one, remove "
                    "it with --center " +
                    c.name);
    }
  }
  return out;
}

std::vector<std::string> identified_equations(const IdentifyResult& r) {
  const Model& model = *r.model;
  const std::vector<ParameterEstimate>& parameters = r.parameters();
  if (r.estimate.status != Estimate::Status::kOk) return {};
  // Sums of coefficient * monomial, in the order the terms first appear.
  using Sum = std::vector<std::pair<Monomial, double>>;
  const auto add = [](Sum& into, const Monomial& m, double c) {
    const auto it =
        std::find_if(into.begin(), into.end(), [&](const auto& t) { return t.first == m; });
    if (it == into.end()) {
      into.emplace_back(m, c);
    } else {
      it->second += c;
    }
  };
  // Terms in the states first (by degree, then in the order of the states), then those with an
  // input, then the constant.
  const std::size_t state_count = model.states().size();
  const auto order = [&](const Monomial& m) {
    int degree = 0, input_degree = 0;
    for (std::size_t v = 0; v < m.size(); ++v) {
      degree += m[v];
      if (v >= state_count) input_degree += m[v];
    }
    const int group = degree == 0 ? 2 : input_degree > 0 ? 1 : 0;
    std::vector<int> key{group, degree};
    for (int e : m) key.push_back(-e);
    return key;
  };
  // "-4*y - 0.5*v + x", terms of zero coefficient left out, "0" for none.
  const auto text = [&](Sum sum) {
    std::stable_sort(sum.begin(), sum.end(),
                     [&](const auto& a, const auto& b) { return order(a.first) < order(b.first); });
    std::string out;
    for (const auto& [m, c] : sum) {
      if (c == 0) continue;
      const bool constant = std::all_of(m.begin(), m.end(), [](int e) { return e == 0; });
      const std::string magnitude = figure(std::abs(c), "%.6g");
      std::string term = constant           ? magnitude
                         : magnitude == "1" ? format_monomial(model, m)
                                            : magnitude + "*" + format_monomial(model, m);
      out += (out.empty() ? (c < 0 ? "-" : "") : (c < 0 ? " - " : " + ")) + term;
    }
    return out.empty() ? std::string("0") : out;
  };
  std::vector<std::string> out;
  for (const Equation& eq : model.equations()) {
    // lhs - rhs = sum of derivative terms + sum of the others = 0.
    std::vector<std::pair<std::pair<int, Monomial>, double>> derivatives;
    Sum rest;
    for (const Term& t : eq.terms) {
      double c = t.coefficient.to_double();
      if (t.parameter >= 0) c *= parameters[static_cast<std::size_t>(t.parameter)].estimate;
      if (t.derivative < 0) {
        add(rest, t.monomial, -c);
        continue;
      }
      const auto key = std::make_pair(t.derivative, t.monomial);
      const auto it = std::find_if(derivatives.begin(), derivatives.end(),
                                   [&](const auto& d) { return d.first == key; });
      if (it == derivatives.end()) {
        derivatives.emplace_back(key, c);
      } else {
        it->second += c;
      }
    }
    const bool constant_factor =
        derivatives.size() == 1 &&
        std::all_of(derivatives[0].first.second.begin(), derivatives[0].first.second.end(),
                    [](int e) { return e == 0; });
    if (constant_factor && derivatives[0].second != 0) {
      // One derivative with a number in front: solved for it.
      for (auto& [m, c] : rest) c /= derivatives[0].second;
      out.push_back(model.states()[static_cast<std::size_t>(derivatives[0].first.first)].name +
                    "' = " + text(rest));
      continue;
    }
    std::stable_sort(derivatives.begin(), derivatives.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::string left;
    for (const auto& [key, c] : derivatives) {
      if (c == 0) continue;
      const std::string name = model.states()[static_cast<std::size_t>(key.first)].name + "'";
      const bool plain =
          std::all_of(key.second.begin(), key.second.end(), [](int e) { return e == 0; });
      const std::string factor = plain ? name : format_monomial(model, key.second) + "*" + name;
      const std::string magnitude = figure(std::abs(c), "%.6g");
      left += (left.empty() ? (c < 0 ? "-" : "") : (c < 0 ? " - " : " + ")) +
              (magnitude == "1" ? factor : magnitude + "*" + factor);
    }
    out.push_back((left.empty() ? std::string("0") : left) + " = " + text(rest));
  }
  return out;
}

std::string status_name(const IdentifyResult& r) {
  switch (r.estimate.status) {
    case Estimate::Status::kRankDeficient:
      return "rank-deficient";
    case Estimate::Status::kNothingIdentifiable:
      return "nothing-identifiable";
    case Estimate::Status::kOk:
      break;
  }
  return doubts(r).empty() ? "ok" : "doubtful";
}

std::vector<std::string> warnings(const IdentifyResult& r) {
  std::vector<std::string> w;
  if (r.estimate.status != Estimate::Status::kOk) w.push_back(r.estimate.message);
  const std::vector<std::string> doubt = doubts(r);
  w.insert(w.end(), doubt.begin(), doubt.end());
  // The optimal weighting that was asked for and could not be made: before the rest.
  for (const std::string& s : r.estimate.warnings) {
    if (s.rfind("no optimally weighted estimate", 0) == 0) w.push_back(s);
  }
  const std::vector<ParameterEstimate>& parameters = r.parameters();
  for (const ParameterEstimate& p : parameters) {
    if (!p.identifiable || !(std::abs(p.std_error) > kWeakRelativeError * std::abs(p.estimate))) {
      continue;
    }
    w.push_back("'" + p.name + "' is weakly determined: its standard error is " +
                figure(100 * p.std_error / std::abs(p.estimate), "%.3g") +
                "% of its value. Excite the system more, add multipliers (--degree) or fix "
                "parameters you know");
  }
  const auto& correlation = r.gmm && !r.estimate.gmm_parameters.empty() ? r.estimate.gmm_correlation
                                                                        : r.estimate.correlation;
  for (std::size_t i = 0; i < correlation.size(); ++i) {
    for (std::size_t j = i + 1; j < correlation.size(); ++j) {
      if (!(std::abs(correlation[i][j]) > kStrongCorrelation)) continue;
      w.push_back("the estimates of '" + parameters[i].name + "' and '" + parameters[j].name +
                  "' are strongly correlated (" + figure(correlation[i][j], "%.3f") +
                  "): the data determine a combination of them better than each");
    }
  }
  std::vector<std::string> rest = data_warnings(r.data);
  for (const ChannelStatistics& c : r.data.channels) {
    const std::optional<double> fraction = c.noise_fraction();
    if (c.is_input || !fraction || *fraction < kNoiseWarning) continue;
    rest.push_back("'" + c.name + "' carries white noise of about " + figure(100 * *fraction) +
                   "% of its standard deviation (the excess of its autocorrelation at lag 0): " +
                   (r.lagged ? "the lagged equations correct its powers, but the estimates are "
                               "less certain and may still be biased"
                             : "it biases the zero-lag estimates (the lagged equations, --lags, "
                               "correct for it in part)"));
  }
  for (const auto& [name, tau] : r.correlation_lags) {
    if (tau > 0) continue;
    rest.push_back("'" + name + "' stays correlated across lags " +
                   std::to_string(r.lagged->first_lag) + ".." + std::to_string(r.lagged->last_lag) +
                   " (its autocorrelation stays above 1/e): the lagged equations see less than a "
                   "correlation time of it; give --lags a longer window (with fewer instruments "
                   "if the moments run out) or keep every n-th sample of the record");
  }
  for (const std::string& s : r.estimate.warnings) {
    if (s.rfind("no optimally weighted estimate", 0) != 0) rest.push_back(s);
  }
  w.insert(w.end(), rest.begin(), rest.end());
  return w;
}

namespace {

std::string number(double x, const char* format = "%.6g") {
  if (std::isnan(x)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

const char* hold_name(InputHold hold) {
  return hold == InputHold::kZeroOrderHold ? "zoh" : "sample";
}

void table(std::ostringstream& out, const std::vector<ParameterEstimate>& parameters) {
  std::size_t width = 9;
  for (const auto& p : parameters) width = std::max(width, p.name.size());
  char line[256];
  std::snprintf(line, sizeof line, "  %-*s  %14s  %12s  %s\n", static_cast<int>(width), "parameter",
                "estimate", "std error", "95% interval");
  out << line;
  for (const auto& p : parameters) {
    const std::string interval = p.fixed ? "fixed"
                                 : p.identifiable
                                     ? "[" + number(p.ci_low) + ", " + number(p.ci_high) + "]"
                                     : "not identifiable";
    std::snprintf(line, sizeof line, "  %-*s  %14s  %12s  %s\n", static_cast<int>(width),
                  p.name.c_str(), number(p.estimate).c_str(), number(p.std_error, "%.3g").c_str(),
                  interval.c_str());
    out << line;
  }
}

// "lagged moment equations at lags 3..300 samples, instruments y, y^3; not measured: v = y';
// 5-point lag stencils".
std::string method_text(const IdentifyResult& r) {
  std::string out = "lagged moment equations at lags " + std::to_string(r.lagged->first_lag) +
                    ".." + std::to_string(r.lagged->last_lag) + " samples, instruments ";
  for (std::size_t i = 0; i < r.lagged->instruments.size(); ++i) {
    out += (i ? ", " : "") + format_monomial(*r.model, r.lagged->instruments[i]);
  }
  for (std::size_t i = 0; i < r.lagged->derivatives.size(); ++i) {
    out += (i ? ", " : "; not measured: ") + r.lagged->derivatives[i];
  }
  out += "; " + std::to_string(2 * r.stencil_reach + 1) + "-point lag stencils";
  std::string noise;
  for (std::size_t c = 0; c < r.noise.size(); ++c) {
    if (r.noise[c] == 0) continue;
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", r.noise[c]);
    noise += (noise.empty() ? "" : ", ") + r.channels[c] + " " + text;
  }
  if (!noise.empty()) out += "\nnoise variances, corrected for in powers of the channels: " + noise;
  return out;
}

// "E[y(t-3)*y^3]": a lagged moment over the named channels.
std::string lagged_moment_text(const std::vector<std::string>& channels, const Moment& m) {
  std::string out;
  for (const MomentFactor& f : m.factors()) {
    out += (out.empty() ? "" : "*") + channels[static_cast<std::size_t>(f.channel)];
    if (f.power > 1) out += "^" + std::to_string(f.power);
    if (f.lag > 0) out += "(t-" + std::to_string(f.lag) + ")";
  }
  return "E[" + (out.empty() ? std::string("1") : out) + "]";
}

}  // namespace

std::string format_text(const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  const DataMoments& d = r.data;
  std::ostringstream out;
  out << "model " << r.model->name() << ", data " << r.data_name << ": " << d.rows << " rows in "
      << d.runs << (d.runs == 1 ? " run" : " runs");
  if (d.time_step) out << ", dt = " << number(*d.time_step);
  out << ", input hold " << hold_name(d.hold) << "\n";
  if (r.lagged) out << method_text(r) << "\n";
  if (!r.centered.empty()) {
    out << "means removed (--center):";
    for (const auto& [name, mean] : r.centered) out << " " << name << " " << number(mean, "%.4g");
    out << "\n";
  }
  out << "\n";
  if (r.gmm && !e.gmm_parameters.empty()) {
    out << "optimally weighted estimate (two-step GMM)\n";
    table(out, e.gmm_parameters);
    out << "\nleast-squares estimate (first step)\n";
  } else {
    out << "least-squares estimate\n";
  }
  table(out, e.parameters);
  const std::vector<std::string> equations = identified_equations(r);
  if (!equations.empty()) {
    out << "\nidentified model\n";
    for (const std::string& line : equations) out << "  " << line << "\n";
  }
  out << "\ndiagnostics\n";
  out << "  status: " << status_name(r) << "\n";
  const std::vector<std::string> all = warnings(r);
  if (all.empty()) out << "  warnings: none\n";
  for (const std::string& w : all) out << "  warning: " << w << "\n";
  out << "  equations: " << e.rows << ", rank " << e.rank << " of " << e.parameters.size()
      << ", condition number " << number(e.condition, "%.3g") << "\n";
  out << "  batches: " << e.batches;
  if (e.dof > 0) {
    const bool ends = r.end_values && r.end_values->unavailable.empty();
    out << "; standard errors from their long-run covariance"
        << (ends ? " and the record's ends" : "") << " on " << number(e.dof, "%.0f")
        << " degrees of freedom";
    if (!e.gmm_parameters.empty()) {
      out << " (optimally weighted: " << number(e.gmm_dof, "%.0f") << ")";
    }
  }
  out << "\n";
  if (e.j_statistic) {
    out << "  J test: J = " << number(*e.j_statistic, "%.4g") << " on " << e.j_dof
        << " degrees of freedom, p = " << number(*e.j_pvalue, "%.3g")
        << (*e.j_pvalue < 0.01 ? " (the model does not fit the data)" : "") << "\n";
  }
  if (const auto& s = r.sampling_bias) {
    out << "  sampling bias at dt (the estimate from every other sample, bias of order dt^"
        << IdentifyResult::SamplingBias::kOrder << "):\n";
    const auto& list = r.parameters();
    for (std::size_t p = 0; p < list.size(); ++p) {
      out << "    " << list[p].name << ": " << number(s->bias[p], "%.3g") << " (every other sample "
          << number(s->coarse[p], "%g") << ", difference error "
          << number(s->difference_error[p], "%.3g") << ")\n";
    }
    out << (s->applied ? "    removed: the estimates above are extrapolated to dt = 0\n"
                       : "    within the errors: not removed\n");
  }
  if (const auto& h = r.held_input) {
    if (h->unavailable.empty()) {
      out << "  held input: moments corrected by -dt^2/12 E[g''] for the kinks it puts at the "
             "samples, which moved the estimates by";
      const auto& list = r.parameters();
      for (std::size_t p = 0; p < list.size(); ++p) {
        out << (p ? ", " : " ") << list[p].name << " " << number(h->shift[p], "%+.3g");
      }
      out << "\n";
    } else {
      out << "  held input: moments not corrected for the kinks it puts at the samples: "
          << h->unavailable << "\n";
    }
  }
  if (const auto& v = r.end_values) {
    out << (v->unavailable.empty()
                ? "  record ends: the errors they leave come from the variances of the states "
                  "there, the batches give the rest\n"
                : "  record ends: the errors they leave come from the batches: " + v->unavailable +
                      "\n");
  }
  if (!e.identities.empty()) {
    out << "  stationarity identities (sample violation, z-score):\n";
    for (const IdentityCheck& c : e.identities) {
      out << "    " << c.identity << ": " << number(c.violation, "%.3g")
          << " (z = " << number(c.z, "%.2f") << ")\n";
    }
  }
  return out.str();
}

std::string format_json(const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  const DataMoments& d = r.data;
  auto parameters = [](const std::vector<ParameterEstimate>& list) {
    std::string out = "{";
    for (std::size_t i = 0; i < list.size(); ++i) {
      const ParameterEstimate& p = list[i];
      out += (i ? ",\n    " : "\n    ") + json_string(p.name) +
             ": {\"estimate\": " + json_number(p.estimate) +
             ", \"std_error\": " + json_number(p.std_error) + ", \"ci95\": [" +
             json_number(p.ci_low) + ", " + json_number(p.ci_high) +
             "], \"identifiable\": " + (p.identifiable ? "true" : "false") +
             ", \"fixed\": " + (p.fixed ? "true" : "false") + "}";
    }
    return out + "\n  }";
  };
  const bool gmm = r.gmm && !e.gmm_parameters.empty();
  std::ostringstream out;
  out << "{\n  \"model\": " << json_string(r.model->name())
      << ",\n  \"data\": " << json_string(r.data_name)
      << ",\n  \"parameters\": " << parameters(gmm ? e.gmm_parameters : e.parameters);
  if (gmm) out << ",\n  \"least_squares\": " << parameters(e.parameters);
  if (r.lagged) {
    out << ",\n  \"method\": {\"name\": \"lagged\", \"lags\": [" << r.lagged->first_lag << ", "
        << r.lagged->last_lag << "], \"stencil_points\": " << 2 * r.stencil_reach + 1
        << ", \"instruments\": [";
    for (std::size_t i = 0; i < r.lagged->instruments.size(); ++i) {
      out << (i ? ", " : "") << json_string(format_monomial(*r.model, r.lagged->instruments[i]));
    }
    out << "], \"not_measured\": " << json_strings(r.lagged->derivatives)
        << ", \"noise_variance\": {";
    for (std::size_t c = 0; c < r.noise.size(); ++c) {
      out << (c ? ", " : "") << json_string(r.channels[c]) << ": " << json_number(r.noise[c]);
    }
    out << "}}";
  }
  if (!r.centered.empty()) {
    out << ",\n  \"centered\": {";
    std::size_t k = 0;
    for (const auto& [name, mean] : r.centered) {
      out << (k++ ? ", " : "") << json_string(name) << ": " << json_number(mean);
    }
    out << "}";
  }
  out << ",\n  \"equations\": " << json_strings(identified_equations(r));
  out << ",\n  \"moments\": {";
  for (std::size_t k = 0; k < d.estimates.mean.size(); ++k) {
    const std::string name = r.lagged ? lagged_moment_text(r.channels, r.lagged_moments[k])
                                      : format_moment(*r.model, r.moments[k]);
    out << (k ? ", " : "") << json_string(name) << ": " << json_number(d.estimates.mean[k]);
  }
  out << "}";
  out << ",\n  \"diagnostics\": {\n    \"status\": " << json_string(status_name(r))
      << ",\n    \"rows\": " << e.rows << ",\n    \"rank\": " << e.rank
      << ",\n    \"condition\": " << json_number(e.condition) << ",\n    \"batches\": " << e.batches
      << ",\n    \"error_dof\": " << json_number(gmm ? e.gmm_dof : e.dof)
      << ",\n    \"samples\": " << d.rows << ",\n    \"runs\": " << d.runs
      << ",\n    \"input_hold\": " << json_string(hold_name(d.hold))
      << ",\n    \"j_statistic\": " << (e.j_statistic ? json_number(*e.j_statistic) : "null")
      << ",\n    \"j_dof\": " << e.j_dof
      << ",\n    \"j_pvalue\": " << (e.j_pvalue ? json_number(*e.j_pvalue) : "null");
  if (const auto& s = r.sampling_bias) {
    out << ",\n    \"sampling_bias\": {\"order\": " << IdentifyResult::SamplingBias::kOrder
        << ", \"applied\": " << (s->applied ? "true" : "false") << ", \"parameters\": {";
    const auto& list = r.parameters();
    for (std::size_t p = 0; p < list.size(); ++p) {
      out << (p ? ", " : "") << json_string(list[p].name)
          << ": {\"coarse\": " << json_number(s->coarse[p])
          << ", \"bias\": " << json_number(s->bias[p])
          << ", \"difference_error\": " << json_number(s->difference_error[p]) << "}";
    }
    out << "}}";
  }
  if (const auto& h = r.held_input) {
    out << ",\n    \"held_input_correction\": {\"applied\": "
        << (h->unavailable.empty() ? "true" : "false");
    if (h->unavailable.empty()) {
      out << ", \"shift\": {";
      const auto& list = r.parameters();
      for (std::size_t p = 0; p < list.size(); ++p) {
        out << (p ? ", " : "") << json_string(list[p].name) << ": " << json_number(h->shift[p]);
      }
      out << "}";
    } else {
      out << ", \"reason\": " << json_string(h->unavailable);
    }
    out << "}";
  }
  if (const auto& v = r.end_values) {
    out << ",\n    \"end_values\": {\"applied\": " << (v->unavailable.empty() ? "true" : "false");
    if (!v->unavailable.empty()) out << ", \"reason\": " << json_string(v->unavailable);
    out << "}";
  }
  out << ",\n    \"identities\": [";
  for (std::size_t i = 0; i < e.identities.size(); ++i) {
    const IdentityCheck& c = e.identities[i];
    out << (i ? ", " : "") << "{\"identity\": " << json_string(c.identity)
        << ", \"violation\": " << json_number(c.violation) << ", \"z\": " << json_number(c.z)
        << "}";
  }
  out << "],\n    \"correlation\": [";
  const auto& correlation = gmm ? e.gmm_correlation : e.correlation;
  for (std::size_t i = 0; i < correlation.size(); ++i) {
    out << (i ? ", " : "") << "[";
    for (std::size_t j = 0; j < correlation[i].size(); ++j) {
      out << (j ? ", " : "") << json_number(correlation[i][j]);
    }
    out << "]";
  }
  out << "],\n    \"warnings\": " << json_strings(warnings(r)) << "\n  }\n}\n";
  return out.str();
}

}  // namespace momentid
