#pragma once

#include <Eigen/Dense>

#include "solve/least_squares.hpp"
#include "solve/linear_system.hpp"
#include "solve/long_run.hpp"

namespace momentid {

// The optimally weighted estimate (GMM): the equations g = A theta - b weighted by the inverse
// of their batch covariance S / B at an estimate `at` (batch_covariance: many degrees of
// freedom; for equations without noise too large by a common factor, which the weights do not
// feel). The estimate's errors and the J test come from the long-run covariance, not from S.
// Needs a first step of full rank and more batches than equations (S has rank B - 1 at most).
struct OptimalWeighting {
  Eigen::MatrixXd weight;  // W = (S / B)^+, rows x rows
  Eigen::Index rank = 0;   // of S: the equations the weighting counts
  // N^-1 = (A' W A)^-1 and N^-1 A' W, in scaled columns (LeastSquares::scale).
  Eigen::MatrixXd information_inverse, left;
  Eigen::VectorXd theta_scaled, theta;
  Eigen::VectorXd residual;  // b - A theta
  // The minimised quadratic form g' W g at theta: Hansen's J statistic, W being the inverse
  // covariance of the record's mean of g rather than of one interval's g.
  double objective = 0;
};

// `series`: the equations' batch series; `known`: a covariance of the moments' record means
// known from elsewhere, added to S.
OptimalWeighting optimal_weighting(const LinearSystem& system, const LeastSquares& first,
                                   const EquationSeries& series, const KnownCovariance& known,
                                   const Eigen::VectorXd& at);

// G K G' at `at`: what `known` adds to the equations' covariance (zero without it).
Eigen::MatrixXd known_part(const LinearSystem& system, const KnownCovariance& known,
                           const Eigen::VectorXd& at);

// The weights taken twice: S at the least-squares estimate gives the pilot (the two-step
// estimate), S at the pilot's estimate the estimate reported. The weights at the least-squares
// estimate carry its errors, many times the weighted estimate's, into the weighted estimate
// (Windmeijer 2005) beyond what the first-order series shows: on the lagged equations of a
// Duffing oscillator with 5% noise (tests/independent/coverage.py) the two-step estimate's z had
// standard deviations of 1.12 and 1.27 for k and eps; 0.96 and 1.00 with the weights taken
// twice and gmm_errors' correction for the step from the pilot.
struct IteratedWeighting {
  OptimalWeighting pilot, weighted;
};
// `twice` false: the pilot alone (`weighted` is the pilot).
IteratedWeighting iterated_weighting(const LinearSystem& system, const LeastSquares& first,
                                     const EquationSeries& series, const KnownCovariance& known,
                                     bool twice);

// The weights come from the same batches as the errors, which makes the batch series of the
// estimate's errors look too small by (n - m + q) / n and the estimate less efficient than with
// known weights by (n - 1) / (n - m + q - 1), for n = B - 1 degrees of freedom of S, m equations
// and q parameters (Gaussian batch means, Wishart S): the product of the two, by which the
// series' covariance is to be multiplied.
double finite_sample_factor(std::size_t batches, Eigen::Index equations, Eigen::Index parameters);

// The errors of the optimally weighted estimate `gmm`: `series`, the batch series of its
// first-order errors with the weights held (parameters unscaled) times the root of
// finite_sample_factor, and `errors`, the long-run covariance of the series plus what the
// moments' known covariance adds. With the `pilot` whose estimate the weights were taken at,
// `errors` also hold what the pilot's batch errors bring through the weights: d theta /
// d theta_pilot times the pilot's first-order errors (Windmeijer's correction). The series
// leaves them out: they grow with the equations' residual, which a wrong model makes large, and
// the comparisons the series serve (the zero-lag check) lost most of their power against wrong
// laws with them.
struct GmmErrors {
  Eigen::MatrixXd series;
  LongRunCovariance errors;
};
GmmErrors gmm_errors(const LinearSystem& system, const LeastSquares& first,
                     const OptimalWeighting& gmm, const EquationSeries& series,
                     const KnownCovariance& known, std::size_t batches,
                     const OptimalWeighting* pilot = nullptr);

}  // namespace momentid
