#pragma once

// The steps of identify(), each a unit that another command (term selection, validation) can
// call: choose the equations for the data, plan the moments of the pass, read them, solve, refine.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "app/variables.hpp"
#include "momentid/derive.hpp"
#include "momentid/estimate.hpp"
#include "momentid/identify.hpp"
#include "momentid/lagged.hpp"
#include "momentid/model.hpp"

namespace momentid {

// Four batches per equation keep the optimal weighting's batch covariance well conditioned.
inline constexpr std::size_t kBatchesPerEquation = 4;

// ---- the plan ---------------------------------------------------------------------------------

enum class EquationKind { kZeroLag, kLagged };

// Which equations identify takes for a record, and why (IdentifyResult::why).
struct EquationChoice {
  EquationKind kind;
  std::string why;
};

// IdentifyOptions::method, or for kAuto: the lagged equations when lags or instruments are given,
// or the record lacks a state they can read as a derivative, or it is measured (not known to be
// noise-free) and gives a sample interval; the zero-lag ones for the rest, and for zero-lag
// options (multipliers, a degree, extrapolate) on records with every state. Models with abs and
// sign terms alike: a record that lacks the column of such a term's argument, while showing
// every state, gets the lagged equations, which refuse the term by name.
EquationChoice choose_equations(const Model& model, const RecordSurvey& record,
                                const IdentifyOptions& options);

// For IdentifyOptions::integrate: the column each named state is formed from (the record must
// show it only as the integral of one) and the filter's corner, given or chosen from the band of
// the record's first input with a column (else of the column integrated); marks the formed
// states present. Throws UsageError naming integrate, DataError for a record without a sample
// interval or too short for its band.
IdentifyResult::Integration plan_integration(const Model& model, const DataSource& source,
                                             const IdentifyOptions& options,
                                             std::vector<bool>& present);

// The state and input names of `model`, in declaration order: the channels of a zero-lag pass.
std::vector<std::string> state_names(const Model& model);
std::vector<std::string> input_names(const Model& model);
// The names of the columns that hold derivatives (Model::measured_derivatives()).
std::vector<std::string> derivative_names(const Model& model);

// The model's abs and sign terms as channels the pass computes; throws ModelError at an equation
// whose function mixes states and inputs.
std::vector<ComputedChannel> computed_channels(const Model& model);

// The options of a pass over the record as `options` ask for it (columns, sample interval,
// layout, input hold, batches, threads), with the autocorrelations the noise estimates need.
DataOptions pass_options(const Model& model, const IdentifyOptions& options);

// The offsets of DataOptions for the channels `states`, `inputs`, then options.derivatives: the
// mean of each channel that `center` names, and of each derivative column (whose true mean is 0,
// so that its mean is an offset) unless options.integration filters every channel, from a pass
// of its own, and 0 for the others; none when no channel is centered. Records the means removed
// in `centered`.
std::vector<double> channel_offsets(const DataSource& source,
                                    const std::vector<std::string>& states,
                                    const std::vector<std::string>& inputs,
                                    const DataOptions& options,
                                    const std::vector<std::string>& center,
                                    std::map<std::string, double>& centered);

// Whether the main estimate is the optimally weighted one (IdentifyOptions::weighting) for a
// system of `equations` equations in `model`'s parameters, some fixed by `options`: by default
// whenever the equations outnumber the free parameters, so that the J test can check the model
// (not with IdentifyOptions::extrapolate, whose two estimates need one weighting).
bool optimal_weighting(const Model& model, const IdentifyOptions& options, std::size_t equations);

// The parameters fixed by IdentifyOptions::fixed or in the model file (the option's value wins),
// as SolveOptions::fixed wants them: per parameter, in declaration order.
std::vector<std::optional<double>> fixed_values(const Model& model,
                                                const std::map<std::string, double>& fixed);

// ---- the channels' means (channel_means.cpp) ----------------------------------------------------

// The first moments E[c] of `channels` channels, as monomials over them (over `variables`
// variables when more, such as a model's functions after its channels), in channel order.
std::vector<Monomial> first_moments_of(std::size_t channels, std::size_t variables = 0);

// Per channel `names[c]`: its mean, the estimate all.mean[index[c]], with the standard error from
// the long-run covariance of its batch series; empty with fewer than two batches.
std::vector<ChannelMean> channel_means(const std::vector<std::string>& names,
                                       const MomentEstimates& all,
                                       const std::vector<std::size_t>& index);

// Adds to the standard error of the mean of each state w that a kinematic equation makes another
// state's derivative (v in y' = v) the error of the record's ends: its mean over a run is
// (y(end) - y(start)) / (ratio T), whose batch series telescopes, so that the batches show
// nearly none of it; the ends, far apart, are independent draws of y, 2 runs Var(y) /
// (ratio T)^2 over the runs. Needs the sample interval; `data` holds the channels' statistics.
void add_end_errors(std::vector<ChannelMean>& means, const Model& model, const DataMoments& data);

// ---- the zero-lag equations ---------------------------------------------------------------------

// The zero-lag moment equations of a model and what one pass over a record must read for them.
struct ZeroLagPlan {
  MomentSystem system;
  std::vector<Monomial> moments;  // the system's, as moments_to_estimate lists them
  // `moments`, then the channels' means, those the held-input correction adds, and the
  // products the record's ends need (unless `ends_unavailable` says why not).
  std::vector<Monomial> pass_moments;
  HeldInputCorrections held;
  std::vector<Monomial> rated;  // the monomials g of the rates of change E[(g)'] in `moments`
  std::string ends_unavailable;
};

// Derives the equations with the record's rates of change kept (DeriveOptions::rates) and plans
// the pass: the held-input correction's moments unless the inputs are known to be sampled, and
// the products of the rated monomials unless these would more than double the pass.
ZeroLagPlan plan_zero_lag(const Model& model, const IdentifyOptions& options);

// The zero-lag identification into `result` (whose model is set): the plan, one pass, the
// solution, and the refinements (held input, sampling bias).
void identify_zero_lag(IdentifyResult& result, const DataSource& source,
                       const IdentifyOptions& options);

// ---- the record's ends (end_values.cpp) -------------------------------------------------------

// The moments the pass reads for `moments` (over the model's variables): a rate of change
// (Monomial::rate()) as the increment of its monomial.
std::vector<Moment> pass_moments_of(const std::vector<Monomial>& moments);

// `moments` without the rates of change.
std::vector<Monomial> without_rates(std::vector<Monomial> moments);

// The monomials g of the rates of change E[(g)'] among `moments`, in their order.
std::vector<Monomial> rate_monomials(const std::vector<Monomial>& moments);

// The products g_i * g_j of the monomials `g` (i <= j), with the g themselves.
std::vector<Monomial> with_products(const std::vector<Monomial>& g);

// Turns the averages of the increments among `moments` (pass_moments_of) into the record's rates
// of change, dividing by the interval `interval` between the rows the pass read; without it, sets
// them to 0 (their stationary value) in every batch.
void increments_to_rates(const std::vector<Monomial>& moments, std::optional<double> interval,
                         MomentEstimates& estimates);

// The covariance of the record's rates of change (g(end) - g(start)) / T summed over its runs,
// for the monomials `g` whose moments and products (with_products) are among `moments` with
// `estimates`: each run's ends, far apart, are independent draws of the stationary states, so
// that the covariance is 2 runs Cov(g_i, g_j) / T^2 (docs/uncertainty.md, "End values").
std::vector<std::vector<double>> rate_covariance(const std::vector<Monomial>& g,
                                                 const std::vector<Monomial>& moments,
                                                 const MomentEstimates& estimates, std::size_t runs,
                                                 double duration);

// ---- moment lists -----------------------------------------------------------------------------

// The moments of `all` at `index`, in that order, overall and per batch.
MomentEstimates moments_at(const MomentEstimates& all, const std::vector<std::size_t>& index);

// The first `count` moments of `all`, overall and per batch.
MomentEstimates first_moments(const MomentEstimates& all, std::size_t count);

// Those of `more` that are neither among `moments` nor the constant 1, each once, in their order.
std::vector<Monomial> not_among(const std::vector<Monomial>& moments,
                                const std::vector<Monomial>& more);

// ---- refinements of the zero-lag estimate ------------------------------------------------------

// The moments the E[g''] of `held` are made of.
std::vector<Monomial> second_derivative_moments(const HeldInputCorrections& held);

// Data whose input is held over each sample: replaces the estimate of `result` by the one from
// moments corrected for the kinks of the held input, E[g] = E_dt[g] - dt^2/12 E[g''] (derive.hpp,
// held_input_corrections), with the weights of E[g''] at the parameters of the previous
// estimate, twice (the second pass changes the estimates by O(dt^4)). `all` holds the moments
// `moments` in that order, the system's first.
void correct_for_held_input(IdentifyResult& result, const HeldInputCorrections& held,
                            const std::vector<Monomial>& moments, const MomentEstimates& all,
                            const SolveOptions& solve_options);

// IdentifyOptions::extrapolate, after the zero-lag estimate `result` (whose first-order errors
// over the batches are result.estimate.error_batches): the same estimate from every other sample
// (both halves of each run, in the same batches), the difference's error from the long-run
// covariance of the difference of the two error series, and Richardson's extrapolation when a
// difference exceeds its error.
void estimate_sampling_bias(IdentifyResult& result, const DataSource& source,
                            DataOptions data_options, const IdentifyOptions& options);

// ---- the lagged equations ----------------------------------------------------------------------

// The lagged identification into `result` (whose model is set): the equations for the lags
// asked for, or for a window the data's correlation times call for, one pass (two when the
// first shows the window far from that), the noise on each state channel, the solution.
// `measured`: per model variable, whether the data have its column.
void identify_lagged(IdentifyResult& result, const DataSource& source,
                     const IdentifyOptions& options, const std::vector<bool>& measured);

// ---- the zero-lag check (zero_lag_check.cpp) ---------------------------------------------------

// The zero-lag check's highest degree and what the lagged pass reads for it.
struct ZeroLagCheckPlan {
  int degree = 0;
  std::optional<MomentSystem> system;  // the zero-lag equations at `degree`
  std::vector<Monomial> moments;       // over the model's variables, with their noise corrections'
  std::string unavailable;             // why no degree fits the check, when none does
};

// The plan of the zero-lag check (IdentifyResult::Lagged::ZeroLagCheck) when the defaults take
// the lagged equations for a record that shows every state and input (`measured`, per model
// variable) in its own column (with `unavailable` set when even degree 1 exceeds the check's
// budget of equations); nullopt otherwise.
std::optional<ZeroLagCheckPlan> plan_zero_lag_check(const Model& model,
                                                    const IdentifyOptions& options,
                                                    const std::vector<bool>& measured);

// The check into result.lagged->zero_lag_check, after the lagged estimate: `moments` are the
// estimates of plan.moments from the same pass (its batches), `channel` the pass's channel per
// model variable. At the highest degree up to plan.degree whose equations keep
// kBatchesPerEquation batches each.
void check_with_zero_lag(IdentifyResult& result, const ZeroLagCheckPlan& plan,
                         const MomentEstimates& moments, const std::vector<int>& channel,
                         const IdentifyOptions& options);

// The equations of `system` (the result's own lagged system, or one derived with its
// instruments at fewer lags) as rows over the moments of the result's pass
// (result.lagged->moments), with the result's noise and stencils.
MomentRows lagged_rows_of(const IdentifyResult& result, const LaggedSystem& system);

}  // namespace momentid
