#pragma once

// The delta method: an estimate's first-order errors as a linear function of the moments' errors,
// whose batch series gives their long-run covariance (solve/long_run.hpp), and the intervals,
// correlations and warnings that come from it.

#include <Eigen/Dense>
#include <vector>

#include "momentid/estimate.hpp"
#include "solve/linear_system.hpp"
#include "solve/long_run.hpp"

namespace momentid {

// Row b: n_b / n (mu_b - mu) for batch b of n_b intervals (n their average) and the record's
// means mu: the batch series that long_run_covariance expects, batches x moments.
Eigen::MatrixXd batch_deviations(const MomentEstimates& estimates);

// The sensitivity d theta / d mu_k of theta = N^-1 A' W b for every moment (parameters x
// moments), with N^-1 = `normal_inverse`, `left` = N^-1 A' W, `weighted_residual` = W (b - A
// theta) and theta = `at`, all in the columns scaled by `scale`; the sensitivity unscaled.
Eigen::MatrixXd sensitivity(const LinearSystem& system, const Eigen::VectorXd& scale,
                            const Eigen::MatrixXd& normal_inverse, const Eigen::MatrixXd& left,
                            const Eigen::VectorXd& weighted_residual, const Eigen::VectorXd& at);

// `errors` of a series x = J mu plus the covariance `added` = J K J' that a known covariance K of
// the moments adds, with the degrees of freedom of the sum (Satterthwaite, K taken as exact: the
// fewest over the series' components).
LongRunCovariance with_known(LongRunCovariance errors, const Eigen::MatrixXd& added);

// cov(i, j) / sqrt(cov(i, i) cov(j, j)), NaN where a variance is not positive or a parameter
// is not identifiable.
std::vector<std::vector<double>> correlation_of(const Eigen::MatrixXd& cov,
                                                const std::vector<bool>& identifiable);

// The rows of a matrix (Estimate::error_batches), and the matrix of `columns` columns they hold.
std::vector<std::vector<double>> rows_of(const Eigen::MatrixXd& matrix);
Eigen::MatrixXd matrix_of(const std::vector<std::vector<double>>& rows, Eigen::Index columns);

// `estimate` with its standard error and the interval estimate -+ t975 standard errors.
void set_error(ParameterEstimate& estimate, double std_error, double t975);

// The warning that says the standard errors take the batch means as independent: too few
// batches for the long-run covariance's spectral fit. (identify's doubts name errors that rest on
// few degrees of freedom.)
void warn_about_errors(Estimate& out, const LongRunCovariance& errors);

}  // namespace momentid
