#include "solve/j_test.hpp"

#include <algorithm>

#include "solve/delta_method.hpp"
#include "solve/distributions.hpp"
#include "solve/long_run.hpp"

namespace momentid {

using Eigen::Index;
using Eigen::MatrixXd;

// The residual g = A theta - b lies in the d = m - q directions that the estimate leaves free,
// with covariance V there: the long-run covariance of the batch series of M g(mu_b), M = I - A
// N^-1 A' W. J = g' W g is then a weighted sum of chi-square variables, with weights the
// eigenvalues of W V, which a scaled chi-square matches in mean and variance (Satterthwaite):
// J / c ~ chi-square(k), c k = tr(W V), c^2 k = tr((W V)^2), the latter less the excess that the
// noise of V, on nu degrees of freedom, adds to it as it does to a Wishart matrix: E tr((W V^)^2)
// = (1 + 1/nu) tr((W V)^2) + tr(W V)^2 / nu. The traces take V before its negative eigenvalues
// are set to zero (LongRunCovariance::linear): most of the d directions may have nearly no
// long-run variance, and zeroing the noise's negative half in each of them made tr(W V) 20% too
// large (the statistic 0.88 of its dof at the true model, a test that never rejected).
//
// W from the same batches makes E[tr(W V)] smaller than E[J]: every batch-mean periodogram
// ordinate that V weighs is also one of the n = B - 1 degrees of freedom of the batch covariance
// that W inverts, which shrinks W along it by about (n - d) / (n - d + d rho), rho = tr(W V) / d
// the long-run variance over the batch variance. Independent batches (rho = 1) give Hotelling's
// T^2, J (n - d) / n over its scale being F(d, n - d + 1); equations whose batch means are
// negatively correlated, as time averages of derivatives are, put V on the low ordinates where
// the batch variance is small (rho well below 1) and the shrinking is milder. So J / (c k) times
// that factor is F(k, nu'), with 1 / nu' = rho / (n - d + 1) + 1 / (k nu): the noise of W, then
// of V, tr(W V) summing k components of nu degrees of freedom each (nu counts those of one
// standardised series). Reported: J d / tr(W V), whose mean is d for the right model whether the
// equations telescope (W too small by a factor near B) or not.
JTest j_test(const LinearSystem& system, const LeastSquares& first, const OptimalWeighting& gmm,
             const EquationSeries& series, const KnownCovariance& known, std::size_t batches) {
  const Index rows = system.a.rows(), params = system.a.cols();
  JTest out;
  out.dof = static_cast<int>(gmm.rank - params);
  if (out.dof <= 0) {
    out.warning = "no J test: as many equations as parameters (add multipliers)";
    return out;
  }
  const auto n = static_cast<double>(batches - 1);
  const auto d = static_cast<double>(out.dof);
  // M g_b for every batch, as g_b less its part along A: (I - A N^-1 A' W) g_b.
  const MatrixXd g = series.at(gmm.theta);
  const MatrixXd free_g = g - (g * gmm.left.transpose()) * first.scaled.transpose();
  const MatrixXd free_part = MatrixXd::Identity(rows, rows) - first.scaled * gmm.left;
  const MatrixXd added = free_part * known_part(system, known, gmm.theta) * free_part.transpose();
  const LongRunCovariance residual_errors = with_known(long_run_covariance(free_g), added);
  const MatrixXd wv = gmm.weight * residual_errors.linear;
  const double nu = residual_errors.dof, trace = wv.trace();
  const double trace_square =
      std::max(((wv * wv).trace() - trace * trace / nu) / (1 + 1 / nu), trace * trace / out.dof);
  if (!(trace > 0 && trace_square > 0)) {
    out.warning = "no J test: the residuals show no sampling error";
    out.dof = 0;
    return out;
  }
  const double j = gmm.objective;
  const double k = trace * trace / trace_square;
  const double rho = trace / d;
  out.statistic = j * out.dof / trace;
  out.law = {k, std::max(1.0, 1 / (rho / (n - d + 1) + 1 / (k * nu))), (n - d) / (n - d + d * rho)};
  out.pvalue =
      f_upper_tail(*out.statistic / d * out.law.scale, out.law.dof, out.law.denominator_dof);
  return out;
}

}  // namespace momentid
