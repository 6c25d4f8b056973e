// The zero-lag moment equations: derived once, their moments read in one pass, solved, refined.

#include "app/identify/zero_lag.hpp"

#include <algorithm>

#include "app/identify/channel_means.hpp"
#include "app/identify/end_values.hpp"
#include "app/identify/held_input.hpp"
#include "app/identify/moment_lists.hpp"
#include "app/identify/pass.hpp"
#include "app/identify/plan.hpp"
#include "app/identify/sampling_bias.hpp"

namespace momentid {

ZeroLagPlan plan_zero_lag(const Model& model, const IdentifyOptions& options) {
  ZeroLagPlan plan;
  DeriveOptions derive_options;
  derive_options.multipliers = options.multipliers;
  derive_options.degree = options.degree;
  derive_options.rates = true;
  plan.system = derive(model, derive_options);
  plan.fixed = fixed_values(model, options.fixed);
  plan.moments = moments_to_estimate(plan.system);
  // A held input puts kinks into the states at the samples: the moments whose derivative
  // holds it are then corrected, with E[g''] from moments the pass adds (unless the data are
  // known to be sampled).
  if (!model.inputs().empty() && options.record.hold != InputHold::kSample) {
    plan.held = held_input_corrections(model, without_rates(plan.moments));
  }
  // The ends of the record: the rates of change, with the products their covariance needs
  // (from a sample of the rows, DataOptions::point_moments), unless these would outnumber the
  // pass's moments.
  plan.rated = rate_monomials(plan.moments);
  plan.pass_moments = plan.moments;
  const std::vector<Monomial> means = not_among(
      plan.pass_moments, first_moments_of(model.channel_count(), model.variables().size()));
  plan.pass_moments.insert(plan.pass_moments.end(), means.begin(), means.end());
  const std::vector<Monomial> kinks =
      not_among(plan.pass_moments, second_derivative_moments(plan.held));
  plan.pass_moments.insert(plan.pass_moments.end(), kinks.begin(), kinks.end());
  const std::vector<Monomial> products = not_among(plan.pass_moments, with_products(plan.rated));
  if (products.size() > plan.pass_moments.size()) {
    plan.ends_unavailable = "their covariance would need " + std::to_string(products.size()) +
                            " more moments than the " + std::to_string(plan.pass_moments.size()) +
                            " the pass reads (the products of " +
                            std::to_string(plan.rated.size()) + " rates of change)";
  }
  return plan;
}

namespace {

// The pass over the record for `plan` into result.data, whose estimates are the system's
// moments; returns the estimates of all the pass moments, the rates of change among them
// divided by the sample interval (or 0 when the ends cannot be used). Updates
// plan.ends_unavailable when the data give no sample interval.
MomentEstimates read_zero_lag(IdentifyResult& result, ZeroLagPlan& plan, const DataSource& source,
                              DataOptions& data_options) {
  const Model& model = *result.model;
  const std::vector<std::string> states = state_names(model), inputs = input_names(model);
  // The correction removes the trapezoidal rule's error on the held products too, which the
  // cubic rule only makes smaller.
  if (!plan.held.moments.empty()) data_options.held_rule = HeldRule::kTrapezoidal;
  const std::vector<Moment> moments = pass_moments_of(plan.pass_moments);
  result.data = moments_from_data(source, states, inputs, moments, data_options);
  if (result.data.hold == InputHold::kZeroOrderHold && !plan.held.moments.empty() &&
      !result.data.time_step) {
    // No correction without the sample interval: the cubic rule then does better.
    data_options.held_rule = HeldRule::kCubic;
    result.data = moments_from_data(source, states, inputs, moments, data_options);
  }
  if (!result.data.time_step && plan.ends_unavailable.empty()) {
    plan.ends_unavailable =
        "the data give no sample interval (a 't' column or a dt in the metadata)";
  }
  // Without their covariance the rates stay out of the batches, whose series then holds the
  // ends.
  increments_to_rates(plan.pass_moments,
                      plan.ends_unavailable.empty() ? result.data.time_step : std::nullopt,
                      result.data.estimates);
  MomentEstimates all = std::move(result.data.estimates);
  result.data.estimates = first_moments(all, plan.moments.size());
  return all;
}

}  // namespace

void identify_zero_lag(IdentifyResult& result, const DataSource& source,
                       const IdentifyOptions& options) {
  const Model& model = *result.model;
  ZeroLagPlan plan = plan_zero_lag(model, options);
  IdentifyResult::ZeroLag& zero_lag = result.zero_lag.emplace();
  zero_lag.system = std::make_shared<const MomentSystem>(plan.system);
  zero_lag.moments = plan.moments;
  result.gmm = optimal_weighting(options, plan.fixed, zero_lag.system->equations.size());
  DataOptions data_options = pass_options(model, options);
  data_options.computed = computed_channels(model);
  // The optimal weighting estimates the equations' covariance from the batches.
  if (result.gmm)
    data_options.min_batches = kBatchesPerEquation * zero_lag.system->equations.size();
  data_options.offsets = channel_offsets(source, state_names(model), input_names(model),
                                         data_options, options.center, result.centered);
  if (!plan.rated.empty() && plan.ends_unavailable.empty()) {
    data_options.point_moments = with_products(plan.rated);
  }
  const MomentEstimates all = read_zero_lag(result, plan, source, data_options);
  data_options.point_moments.clear();
  std::vector<std::size_t> mean_index;
  for (const Monomial& m : first_moments_of(model.channel_count(), model.variables().size())) {
    mean_index.push_back(
        static_cast<std::size_t>(std::find(plan.pass_moments.begin(), plan.pass_moments.end(), m) -
                                 plan.pass_moments.begin()));
  }
  result.means = channel_means(model.channel_names(), all, mean_index);
  add_end_errors(result.means, model, result.data);

  SolveOptions solve_options{.gmm = result.gmm, .fixed = plan.fixed};
  if (!plan.rated.empty()) {
    zero_lag.end_values.emplace().unavailable = plan.ends_unavailable;
    if (plan.ends_unavailable.empty() && result.data.estimates.intervals > 0) {
      solve_options.rate_covariance = rate_covariance(
          plan.rated, result.data.point_means, std::max<std::size_t>(result.data.runs, 1),
          static_cast<double>(result.data.estimates.intervals) * *result.data.time_step);
    }
  }
  result.estimate = solve(*zero_lag.system, zero_lag.moments, result.data.estimates, solve_options);
  if (result.data.hold == InputHold::kZeroOrderHold) {
    correct_for_held_input(result, plan.held, plan.pass_moments, all, solve_options);
  }
  if (options.extrapolate) estimate_sampling_bias(result, source, data_options, plan.fixed);
}

}  // namespace momentid
