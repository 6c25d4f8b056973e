#pragma once
// What a solve yields: the parameters' estimates with their errors and the diagnostics. These
// are plain values, free of the symbolic model (estimate.hpp has the solver that makes them), so
// that code which only reads a result needs no computer-algebra headers.

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "momentid/types.hpp"

namespace momentid {

// One parameter's estimate. `identifiable` is false when the data determine only combinations
// of this parameter with others (then the estimate is the minimum-norm one and the error NaN).
struct ParameterEstimate {
  std::string name;
  double estimate = 0;
  double std_error = 0;
  double ci_low = 0, ci_high = 0;  // 95% interval
  bool identifiable = true;
  bool fixed = false;  // given, not estimated (SolveOptions::fixed): error 0
};

// The sample violation of a pure-data identity E[m] = value, in standard errors.
struct IdentityCheck {
  std::string identity;
  double violation = 0;
  double z = 0;
};

// One estimate of the parameters with its errors: the least-squares fit, or the optimally
// weighted (GMM) one (SolveOptions::iterate_weights: its weights taken a second time).
struct Fit {
  std::vector<ParameterEstimate> parameters;
  // The estimates' correlation matrix, parameter by parameter (NaN where a parameter is not
  // identifiable or has no standard error); empty with fewer than two batches.
  std::vector<std::vector<double>> correlation;
  // Degrees of freedom of the standard errors (long_run_covariance): the 95% intervals take
  // Student's t quantile at them.
  double dof = 0;
  // What the fit minimised, at its estimate. Fits of the same moment estimates with the same
  // weights compare by it: other parameter subsets (SolveOptions::fixed at 0 drops a term) or
  // other systems over the same moments.
  //
  // Least squares: the weighted sum of squared row residuals sum_r w_r^2 (b_r - a_r theta)^2,
  // with w_r = 1, or 1 / |a_r| with SolveOptions::normalise_rows (|a_r| over the free
  // parameters, so that subsets weight their rows alike only where the rows keep their lengths).
  // NaN when nothing is identifiable.
  //
  // Optimally weighted: Hansen's objective g' Omega^+ g for g = A theta - b (rows weighted as
  // above), where Omega = T S / B is the covariance of one interval's g that the weighting used:
  // S / B that of g's record mean, from its batch means at the least-squares estimate, and T =
  // Estimate::intervals (NaN when 0). T * objective = g' (S / B)^+ g is Hansen's J statistic;
  // Estimate::j_statistic reports it calibrated for weights and errors from the same batches,
  // times j_dof / tr(W V) (solve/j_test.cpp), a factor of 1 when the residual's long-run
  // covariance V is the projection of S / B (fewer than kMinSpectralBatches batches,
  // coefficients free of moments).
  double objective = std::numeric_limits<double>::quiet_NaN();

  // The estimates' covariance matrix, from their standard errors and correlation: 0 in the row
  // and column of a fixed parameter, NaN where an error is unknown.
  std::vector<std::vector<double>> covariance() const;
};

// The law of the J test's p-value (solve/j_test.cpp): J / j_dof times `scale` (the shrinking of
// weights estimated from the batches that also give the errors) is taken as F(dof,
// denominator_dof), where dof counts the effective directions of the residual's long-run
// variance (Satterthwaite) and denominator_dof the degrees of freedom that variance and the
// weights are known to.
struct JLaw {
  double dof = 0, denominator_dof = 0, scale = 1;
};

// The result of an identification: the least-squares fit and, when asked for and possible, the
// optimally weighted one, with the diagnostics that say when to distrust them. Like a solver
// summary, it is a value even when the answer is poor: `status` and `warnings` say so.
struct Estimate {
  Status status = Status::kOk;  // never kDoubtful: doubts are the application's (identify.hpp)
  std::string message;          // what went wrong, for kRankDeficient and kNothingIdentifiable

  Fit least_squares;
  std::optional<Fit> optimal;  // optimal weighting (SolveOptions::gmm), when computed
  std::size_t rows = 0;        // equations in the system
  std::size_t rank = 0;
  double condition = 0;  // of the column-scaled coefficient matrix
  std::size_t batches = 0;
  std::size_t intervals = 0;  // sample intervals the moments average over
  std::optional<double> j_statistic, j_pvalue;
  int j_dof = 0;
  JLaw j_law;  // of j_pvalue
  // The batch series of the main fit's first-order errors, batches x parameters, whose long-run
  // covariance gives its standard errors (zero columns for fixed parameters); empty when nothing
  // is identifiable. As solve computed it: identify's extrapolation of the sampling bias leaves
  // it as it was.
  std::vector<std::vector<double>> error_batches;
  std::vector<IdentityCheck> identities;
  std::vector<std::string> warnings;

  // The optimally weighted fit when there is one, otherwise least squares.
  const Fit& main() const { return optimal ? *optimal : least_squares; }
  Fit& main() { return optimal ? *optimal : least_squares; }
  // Whether every parameter has an estimate and an error: the status is kOk (a rank-deficient
  // estimate has minimum-norm values only).
  bool usable() const { return status == Status::kOk; }
  // The p-value below which a test of the model (J, and the latent path's Q) rejects it.
  static constexpr double kJRejection = 0.01;
};

}  // namespace momentid
