#pragma once

// Term selection on one fixed weighting (docs/cli/select.md): the moment equations of a library
// of terms, weighted once at the library's own first-step estimate, give every subset of its
// parameters a J statistic by a small least-squares solve, so that subsets are compared on the
// same scale and none needs the data again.

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "momentid/estimate.hpp"
#include "momentid/fit.hpp"

namespace momentid {

class FixedWeighting {
 public:
  // The equations `rows` (over `parameters` parameters) at `estimates`, weighted by the inverse
  // batch covariance of the equations at the library's least-squares estimate, as the optimal
  // weighting of solve_rows is. Throws Error when the library's equations cannot be weighted
  // (rank-deficient, fewer batches than rows plus two, no more equations than parameters, or no
  // sampling error to calibrate J by): `what` names the library in the message.
  // `deviations`: the moments' batch series, batch_deviations(estimates), which the weightings
  // of one library's windows share. `moment_variance`: as SolveOptions::moment_variance.
  FixedWeighting(const MomentRows& rows, std::size_t parameters, const MomentEstimates& estimates,
                 const Eigen::MatrixXd& deviations, const std::vector<double>& moment_variance,
                 bool normalise_rows, const std::string& what);

  // J of the subset `kept` (a flag per parameter): the library's calibrated J test statistic
  // (j_test) plus the Wald statistic of the parameters the subset drops, on the library's
  // estimate and its covariance as identify reports it (the long-run covariance of the errors'
  // batch series, times the finite-sample factor of the estimated weights, gmm.hpp). So a
  // subset's J less the library's is asymptotically chi-square in the parameters dropped, and for
  // one parameter the square of the t statistic that identify prints for it on the library.
  double j(const std::vector<bool>& kept) const;
  // The equations the weighting counts less the parameters `kept` holds: J's degrees of freedom.
  int dof(const std::vector<bool>& kept) const;
  // The correlation between the estimates of parameters p and q on the library.
  double correlation(std::size_t p, std::size_t q) const;
  // The p-value of J(kept) on the J test's law (JLaw, fit.hpp): the library's J, of mean d on k
  // effective directions, plus a Wald statistic of chi-square(q) for the q parameters dropped,
  // matched in mean and variance by an F of k' = (d + q)^2 / (d^2 / k + q) degrees of freedom
  // (Satterthwaite) over the library's denominator; for the library itself its J test's p-value.
  double pvalue(const std::vector<bool>& kept) const;

 private:
  // The library's estimate and its covariance, and its calibrated J: a subset's J is the
  // library's plus the Wald form of the parameters it drops, which stays exact where J is tiny
  // against b' W b (records without noise).
  Eigen::VectorXd theta_;
  Eigen::MatrixXd covariance_;
  double library_j_ = 0;
  JLaw library_law_;
  Eigen::Index rank_ = 0;
};

}  // namespace momentid
