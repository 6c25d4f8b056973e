#include "solve/selection.hpp"

#include <algorithm>
#include <cmath>

#include "momentid/error.hpp"
#include "solve/delta_method.hpp"
#include "solve/distributions.hpp"
#include "solve/gmm.hpp"
#include "solve/j_test.hpp"
#include "solve/least_squares.hpp"
#include "solve/linear_system.hpp"

namespace momentid {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

FixedWeighting::FixedWeighting(const MomentRows& rows, std::size_t parameters,
                               const MomentEstimates& estimates, const MatrixXd& deviations,
                               const std::vector<double>& moment_variance, bool normalise_rows,
                               const std::string& what) {
  const auto params = static_cast<Index>(parameters);
  check_shape(rows, params, estimates.mean.size());
  const LinearSystem system = evaluate(rows, params, estimates.mean, normalise_rows);
  const LeastSquares ls = least_squares(system);
  if (ls.rank < params) {
    throw Error(what + ": the library's equations are rank-deficient (rank " +
                std::to_string(ls.rank) + " of " + std::to_string(params) +
                " parameters): some of its terms cannot be told apart on these data");
  }
  const std::size_t batches = estimates.batch_means.size();
  if (batches < rows.a.size() + 2) {
    throw Error(what + ": weighting the library's " + std::to_string(rows.a.size()) +
                " equations needs more batches than equations, found " + std::to_string(batches));
  }
  const KnownCovariance known = diagonal_covariance(moment_variance, estimates);
  const EquationSeries series(system, deviations);
  const OptimalWeighting gmm = optimal_weighting(system, ls, series, known, ls.theta);
  const JTest test = j_test(system, ls, gmm, series, known, batches);
  if (!test.statistic || !(gmm.objective > 0)) {
    throw Error(what + ": the library's J statistic cannot be calibrated (" +
                (test.warning.empty() ? std::string("no residual") : test.warning) + ")");
  }
  library_j_ = *test.statistic;
  library_law_ = test.law;
  rank_ = gmm.rank;
  theta_ = gmm.theta;
  covariance_ = gmm_errors(system, ls, gmm, series, known, batches).errors.covariance;
}

double FixedWeighting::j(const std::vector<bool>& kept) const {
  // J(theta) = J + (theta - theta^)' N (theta - theta^), least over theta with the dropped
  // parameters D at 0: J + theta^_D' ((N^-1)_DD)^-1 theta^_D.
  std::vector<Index> dropped;
  for (std::size_t p = 0; p < kept.size(); ++p) {
    if (!kept[p]) dropped.push_back(static_cast<Index>(p));
  }
  const auto n = static_cast<Index>(dropped.size());
  VectorXd q(n);
  MatrixXd m(n, n);
  for (Index i = 0; i < n; ++i) {
    const Index a = dropped[static_cast<std::size_t>(i)];
    q(i) = theta_(a);
    for (Index k = 0; k < n; ++k) m(i, k) = covariance_(a, dropped[static_cast<std::size_t>(k)]);
  }
  const double added = n > 0 ? q.dot(m.ldlt().solve(q)) : 0.0;
  return library_j_ + std::max(0.0, added);
}

int FixedWeighting::dof(const std::vector<bool>& kept) const {
  return static_cast<int>(rank_) - static_cast<int>(std::count(kept.begin(), kept.end(), true));
}

double FixedWeighting::pvalue(const std::vector<bool>& kept) const {
  const double d = static_cast<double>(rank_) - static_cast<double>(kept.size());
  const double q = static_cast<double>(std::count(kept.begin(), kept.end(), false));
  const double k = (d + q) * (d + q) / (d * d / library_law_.dof + q);
  return f_upper_tail(j(kept) / (d + q) * library_law_.scale, k, library_law_.denominator_dof);
}

double FixedWeighting::correlation(std::size_t p, std::size_t q) const {
  const auto i = static_cast<Index>(p), k = static_cast<Index>(q);
  return covariance_(i, k) / std::sqrt(covariance_(i, i) * covariance_(k, k));
}

}  // namespace momentid
