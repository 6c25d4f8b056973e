// The sampling bias of the zero-lag estimate (IdentifyOptions::extrapolate): the estimate again
// from every other sample, and Richardson's extrapolation to dt = 0.

#include "app/identify/sampling_bias.hpp"

#include <algorithm>
#include <cmath>

#include "app/identify/end_values.hpp"
#include "app/identify/moment_lists.hpp"
#include "app/identify/pass.hpp"
#include "momentid/estimate.hpp"
#include "solve/long_run.hpp"

namespace momentid {

namespace {

// The zero-lag moments of `result` from every other sample, both halves of each run averaged,
// in the same batches as the record's (`batches` of them).
MomentEstimates every_other_sample(const IdentifyResult& result, const DataSource& source,
                                   DataOptions data_options, std::size_t batches) {
  const Model& model = *result.model;
  data_options.stride = 2;
  data_options.record.hold = result.data.hold;
  // The same batches: the accumulator keeps as many stretches, each of half as many intervals
  // (every other sample), so that they cover the same times as the record's, and the same
  // count of them make a batch.
  if (data_options.batches == 0) {
    data_options.min_batches = std::max(data_options.min_batches, batches);
  }
  MomentEstimates coarse;
  for (std::size_t phase = 0; phase < 2; ++phase) {
    data_options.phase = phase;
    DataMoments pass = moments_from_data(source, state_names(model), input_names(model),
                                         pass_moments_of(result.zero_lag->moments), data_options);
    MomentEstimates& half = pass.estimates;
    increments_to_rates(result.zero_lag->moments, pass.time_step, half);  // at 2 dt
    if (half.batch_means.size() != batches) {
      throw Error(source.name() + ": every other sample gives " +
                  std::to_string(half.batch_means.size()) + " batches, not " +
                  std::to_string(batches) +
                  ": too short a record for the sampling bias (use --batches)");
    }
    if (phase == 0) {
      coarse = half;
      continue;
    }
    for (std::size_t k = 0; k < coarse.mean.size(); ++k) {
      coarse.mean[k] = (coarse.mean[k] + half.mean[k]) / 2;
      for (std::size_t b = 0; b < batches; ++b) {
        coarse.batch_means[b][k] = (coarse.batch_means[b][k] + half.batch_means[b][k]) / 2;
      }
    }
    for (std::size_t b = 0; b < batches; ++b) coarse.batch_intervals[b] += half.batch_intervals[b];
    coarse.intervals += half.intervals;
  }
  return coarse;
}

}  // namespace

void estimate_sampling_bias(IdentifyResult& result, const DataSource& source,
                            DataOptions data_options,
                            const std::vector<std::optional<double>>& fixed) {
  if (!result.model->inputs().empty() && result.data.hold == InputHold::kZeroOrderHold) {
    throw UsageError(
        "extrapolate",
        "the input is held over each sample (input hold zoh): every other sample "
        "of such a record is not the record sampled at 2 dt, whose input would be held over "
        "2 dt; the kinks of the held input are corrected from the model instead");
  }
  Estimate& fine = result.estimate;
  const std::vector<std::vector<double>> fine_errors = fine.error_batches;
  if (fine_errors.empty() || fine.status != Status::kOk) return;
  const MomentEstimates coarse = every_other_sample(result, source, data_options, fine.batches);
  const Estimate c = solve(*result.zero_lag->system, result.zero_lag->moments, coarse,
                           {.gmm = result.gmm, .fixed = fixed});
  const std::vector<std::vector<double>>& coarse_errors = c.error_batches;
  Fit& fine_fit = fine.main();
  std::vector<ParameterEstimate>& list = fine_fit.parameters;
  const std::vector<ParameterEstimate>& coarse_list = c.main().parameters;
  if (c.status != Status::kOk || coarse_errors.size() != fine_errors.size() ||
      coarse_list.size() != list.size()) {
    fine.warnings.push_back("no sampling bias: every other sample does not give an estimate");
    return;
  }
  // theta(h) = theta(0) + C h^p: the bias at dt is (theta(2 dt) - theta(dt)) / (2^p - 1).
  const double r = 1 / (std::pow(2.0, IdentifyResult::ZeroLag::SamplingBias::kOrder) - 1);
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
  IdentifyResult::ZeroLag::SamplingBias bias;
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
    fine_fit.dof = errors.dof;
  }
  result.zero_lag->sampling_bias = std::move(bias);
}

}  // namespace momentid
