#pragma once

#include <Eigen/Dense>

#include "solve/least_squares.hpp"
#include "solve/linear_system.hpp"
#include "solve/long_run.hpp"

namespace momentid {

// The two-step optimally weighted estimate (GMM): the equations g = A theta - b weighted by the
// inverse of their batch covariance S / B at the first-step (least-squares) estimate
// (batch_covariance: many degrees of freedom; for equations without noise too large by a common
// factor, which the weights do not feel). The estimate's errors and the J test come from the
// long-run covariance, not from S. Needs a first step of full rank and more batches than
// equations (S has rank B - 1 at most).
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

// `deviations`: the moments' batch series (batch_deviations); `known`: a covariance of the
// moments' record means known from elsewhere, added to S.
OptimalWeighting optimal_weighting(const LinearSystem& system, const LeastSquares& first,
                                   const Eigen::MatrixXd& deviations, const KnownCovariance& known);

// The weights come from the same batches as the errors, which makes the batch series of the
// estimate's errors look too small by (n - m + q) / n and the estimate less efficient than with
// known weights by (n - 1) / (n - m + q - 1), for n = B - 1 degrees of freedom of S, m equations
// and q parameters (Gaussian batch means, Wishart S): the product of the two, by which the
// series' covariance is to be multiplied.
double finite_sample_factor(std::size_t batches, Eigen::Index equations, Eigen::Index parameters);

// The errors of the optimally weighted estimate: `series`, the batch series of its first-order
// errors (parameters unscaled) times the root of finite_sample_factor, and `errors`, their
// long-run covariance plus what the moments' known covariance adds.
struct GmmErrors {
  Eigen::MatrixXd series;
  LongRunCovariance errors;
};
GmmErrors gmm_errors(const LinearSystem& system, const LeastSquares& first,
                     const OptimalWeighting& gmm, const Eigen::MatrixXd& deviations,
                     const KnownCovariance& known, std::size_t batches);

}  // namespace momentid
