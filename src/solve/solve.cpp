// The solver: least squares, its errors by the delta method, and the optimally weighted estimate
// with its J test, each step in its own file; this one puts them in order.

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "momentid/estimate.hpp"
#include "solve/delta_method.hpp"
#include "solve/fixed.hpp"
#include "solve/gmm.hpp"
#include "solve/identities.hpp"
#include "solve/j_test.hpp"
#include "solve/least_squares.hpp"
#include "solve/linear_system.hpp"
#include "solve/long_run.hpp"
#include "solve/numbers.hpp"
#include "solve/rows.hpp"

namespace momentid {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// What the solver reads from the moments: their batch series and a covariance of their record
// means known from elsewhere (solve: the rates'), added to the errors.
struct MomentErrors {
  const MatrixXd& deviations;
  const KnownCovariance& known;
};

// The covariance that the known covariance of the moments adds to a series J mu.
MatrixXd added_by(const MomentErrors& moments, const MatrixXd& jacobian) {
  return jacobian * moments.known * jacobian.transpose();
}

// The least-squares estimate's parameters, errors, correlations and objective.
// A standard error from a variance: rounding may leave a zero variance slightly negative; a
// variance that is not a number (equations beyond doubles) gives none.
double error_of(double variance) {
  return std::isnan(variance) ? kNaN : std::sqrt(std::max(0.0, variance));
}

void report_least_squares(Estimate& out, const LinearSystem& system, const LeastSquares& ls,
                          const std::vector<bool>& identifiable, const MomentErrors& moments) {
  const MatrixXd jacobian =
      sensitivity(system, ls.scale, ls.normal_pinv, ls.pinv, ls.residual, ls.theta_scaled);
  const MatrixXd series = moments.deviations * jacobian.transpose();
  const LongRunCovariance errors =
      with_known(long_run_covariance(series), added_by(moments, jacobian));
  out.error_batches = rows_of(series);
  Fit& fit = out.least_squares;
  fit.objective = ls.residual.squaredNorm();
  fit.dof = errors.dof;
  const double t975 = out.batches >= 2 ? errors.t975() : kNaN;
  for (std::size_t p = 0; p < fit.parameters.size(); ++p) {
    ParameterEstimate& e = fit.parameters[p];
    const auto i = static_cast<Index>(p);
    e.estimate = ls.theta(i);
    e.identifiable = identifiable[p];
    const bool has_error = e.identifiable && out.batches >= 2;
    set_error(e, has_error ? error_of(errors.covariance(i, i)) : kNaN, t975);
  }
  if (out.batches >= 2) fit.correlation = correlation_of(errors.covariance, identifiable);
  warn_about_errors(out, errors);
}

// The optimally weighted estimate's parameters, errors and objective, and the J test.
void report_gmm(Estimate& out, const LinearSystem& system, const LeastSquares& ls,
                const std::vector<bool>& identifiable, const MomentErrors& moments, bool iterate) {
  const EquationSeries equations(system, moments.deviations);
  const IteratedWeighting steps = iterated_weighting(system, ls, equations, moments.known, iterate);
  const OptimalWeighting& gmm = steps.weighted;
  const auto [series, errors] = gmm_errors(system, ls, gmm, equations, moments.known, out.batches,
                                           iterate ? &steps.pilot : nullptr);
  out.error_batches = rows_of(series);
  Fit& fit = out.optimal.emplace();
  fit.objective = out.intervals > 0 ? gmm.objective / static_cast<double>(out.intervals) : kNaN;
  fit.dof = errors.dof;
  const double t975 = errors.t975();
  for (std::size_t p = 0; p < out.least_squares.parameters.size(); ++p) {
    const auto i = static_cast<Index>(p);
    ParameterEstimate e{out.least_squares.parameters[p].name};
    e.estimate = gmm.theta(i);
    set_error(e, error_of(errors.covariance(i, i)), t975);
    fit.parameters.push_back(e);
  }
  fit.correlation = correlation_of(errors.covariance, identifiable);

  // The J test at the pilot: the two-step J, whose law and power the studies measured
  // (docs/uncertainty.md); at weights taken from a wrong model's estimate its residual inflates
  // S, and J lost a third of its power against a wrong damping law.
  const JTest test = j_test(system, ls, steps.pilot, equations, moments.known, out.batches);
  out.j_dof = test.dof;
  out.j_statistic = test.statistic;
  out.j_pvalue = test.pvalue;
  out.j_law = test.law;
  if (!test.warning.empty()) out.warnings.push_back(test.warning);
}

// Why there is no optimally weighted estimate, or empty.
std::string no_gmm(const Estimate& out, const LeastSquares& ls) {
  if (ls.rank < ls.scale.size()) {
    return "no optimally weighted estimate: the system is rank-deficient";
  }
  // S has rank B - 1 at most: with as many equations or more it is singular and the weighting
  // meaningless.
  if (out.batches < out.rows + 2) {
    return "no optimally weighted estimate: it needs more batches than equations (" +
           std::to_string(out.batches) + " batches for " + std::to_string(out.rows) +
           " equations): use --batches";
  }
  return "";
}

// solve_on without fixed parameters.
Estimate solve_free(const MomentRows& rows, const std::vector<std::string>& names,
                    const MomentEstimates& estimates, const SolveOptions& options,
                    const MomentErrors& moments) {
  Estimate out;
  out.rows = rows.a.size();
  out.batches = estimates.batch_means.size();
  out.intervals = estimates.intervals;
  for (const std::string& name : names) {
    out.least_squares.parameters.push_back({name, kNaN, kNaN, kNaN, kNaN, /*identifiable=*/false});
  }
  if (rows.a.empty() || names.empty()) {
    out.status = Status::kNothingIdentifiable;
    out.message = "the model gives no moment equations";
    return out;
  }
  const LinearSystem system =
      evaluate(rows, static_cast<Index>(names.size()), estimates.mean, options.normalise_rows);
  if (!system.a.allFinite() || !system.b.allFinite()) {
    // A moment beyond doubles (a value whose powers overflow): any solution would be noise.
    out.status = Status::kNothingIdentifiable;
    out.message =
        "the moment equations hold values beyond the range of doubles: the record "
        "has a value too large for the powers of it the equations take";
    return out;
  }
  const LeastSquares ls = least_squares(system);
  out.rank = static_cast<std::size_t>(ls.rank);
  out.condition = ls.condition;
  if (ls.rank == 0) {
    out.status = Status::kNothingIdentifiable;
    out.message = "the moment equations are all zero for these data";
    return out;
  }
  const Identifiability identified = identifiability(ls, names);
  if (!identified.message.empty()) {
    out.status = Status::kRankDeficient;
    out.message = identified.message;
  }
  report_least_squares(out, system, ls, identified.identifiable, moments);
  if (out.condition > 1e8) {
    out.warnings.push_back("the equations are ill-conditioned (condition number " +
                           format_number(out.condition) +
                           "): the parameters are nearly inseparable with these multipliers");
  }
  if (!options.gmm) return out;
  if (const std::string why = no_gmm(out, ls); !why.empty()) {
    out.warnings.push_back(why);
    return out;
  }
  report_gmm(out, system, ls, identified.identifiable, moments, options.iterate_weights);
  return out;
}

// solve_rows with the moments' batch series and known covariance at hand.
Estimate solve_on(const MomentRows& rows, const std::vector<std::string>& names,
                  const MomentEstimates& estimates, const SolveOptions& options,
                  const MomentErrors& moments) {
  check_shape(rows, static_cast<Index>(names.size()), estimates.mean.size());
  const auto& fixed = options.fixed;
  if (std::none_of(fixed.begin(), fixed.end(), [](const auto& v) { return v.has_value(); })) {
    return solve_free(rows, names, estimates, options, moments);
  }
  if (fixed.size() != names.size()) {
    throw std::invalid_argument("solve_rows: one fixed value or nullopt per parameter needed");
  }
  std::vector<std::string> free_names;
  for (std::size_t p = 0; p < names.size(); ++p) {
    if (!fixed[p]) free_names.push_back(names[p]);
  }
  return with_fixed(solve_free(without_fixed(rows, fixed), free_names, estimates, options, moments),
                    names, fixed);
}

// The estimates with the record's rates of change at their stationary value, 0, and the known
// covariance of all the moments' means: options.rate_covariance over the rates, else 0.
std::pair<MomentEstimates, KnownCovariance> at_rest(const std::vector<Monomial>& moments,
                                                    MomentEstimates estimates,
                                                    const SolveOptions& options) {
  std::vector<std::size_t> rates;
  for (std::size_t k = 0; k < moments.size(); ++k) {
    if (!moments[k].rate()) continue;
    estimates.mean[k] = 0;
    rates.push_back(k);
  }
  const auto k = static_cast<Index>(moments.size());
  KnownCovariance known(k, k);
  if (options.rate_covariance.empty()) return {std::move(estimates), known};
  if (options.rate_covariance.size() != rates.size()) {
    throw std::invalid_argument("solve: rate_covariance must be square over the system's rates");
  }
  std::vector<Eigen::Triplet<double>> entries;
  for (std::size_t i = 0; i < rates.size(); ++i) {
    for (std::size_t j = 0; j < rates.size(); ++j) {
      entries.emplace_back(static_cast<Index>(rates[i]), static_cast<Index>(rates[j]),
                           options.rate_covariance[i].at(j));
    }
  }
  known.setFromTriplets(entries.begin(), entries.end());
  return {std::move(estimates), known};
}

}  // namespace

Estimate solve(const MomentSystem& system, const std::vector<Monomial>& moments,
               const MomentEstimates& estimates, const SolveOptions& options) {
  const Model& model = *system.model;
  const std::vector<Monomial> needed = moments_to_estimate(system);
  const MomentEstimates own = estimates_of(needed, moments, estimates, model, "solve");
  const MomentRows rows = moment_rows(system, positions(needed));
  std::vector<std::string> names;
  for (const Declaration& p : model.parameters()) names.push_back(p.name);
  const MatrixXd deviations = batch_deviations(own);
  const auto [rest, known] = at_rest(needed, own, options);
  Estimate out = solve_on(rows, names, rest, options, {deviations, known});
  out.identities = identity_checks(system, needed, own, deviations);
  return out;
}

Estimate solve_rows(const MomentRows& rows, const std::vector<std::string>& names,
                    const MomentEstimates& estimates, const SolveOptions& options) {
  const MatrixXd deviations = batch_deviations(estimates);
  const KnownCovariance known = diagonal_covariance(options.moment_variance, estimates);
  return solve_on(rows, names, estimates, options, {deviations, known});
}

}  // namespace momentid
