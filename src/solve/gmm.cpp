#include "solve/gmm.hpp"

#include <cmath>

#include "solve/delta_method.hpp"
#include "solve/long_run.hpp"

namespace momentid {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

OptimalWeighting optimal_weighting(const LinearSystem& system, const LeastSquares& first,
                                   const MatrixXd& deviations, const KnownCovariance& known) {
  const Index rows = system.a.rows(), params = system.a.cols();
  const Eigen::SparseMatrix<double> g_mu = equations_jacobian(system, first.theta);
  const MatrixXd s =
      batch_covariance(deviations * g_mu.transpose()) + MatrixXd(g_mu * known * g_mu.transpose());
  Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(s);
  const VectorXd lambda = eigen.eigenvalues();
  const double lambda_max = lambda.maxCoeff();
  VectorXd inverse_lambda = VectorXd::Zero(rows);
  OptimalWeighting out;
  for (Index i = 0; i < rows; ++i) {
    if (lambda(i) > 1e-12 * lambda_max) {
      inverse_lambda(i) = 1 / lambda(i);
      ++out.rank;
    }
  }
  out.weight =
      eigen.eigenvectors() * inverse_lambda.asDiagonal() * eigen.eigenvectors().transpose();
  const MatrixXd& as = first.scaled;
  const MatrixXd information = as.transpose() * out.weight * as;
  out.information_inverse = information.ldlt().solve(MatrixXd::Identity(params, params));
  out.left = out.information_inverse * as.transpose() * out.weight;
  out.theta_scaled = out.left * system.b;
  out.theta = out.theta_scaled.cwiseQuotient(first.scale);
  out.residual = system.b - as * out.theta_scaled;
  out.objective = out.residual.dot(out.weight * out.residual);
  return out;
}

double finite_sample_factor(std::size_t batches, Index equations, Index parameters) {
  const auto n = static_cast<double>(batches - 1);
  const auto m = static_cast<double>(equations);
  const auto q = static_cast<double>(parameters);
  return n * (n - 1) / ((n - m + q) * (n - m + q - 1));
}

GmmErrors gmm_errors(const LinearSystem& system, const LeastSquares& first,
                     const OptimalWeighting& gmm, const MatrixXd& deviations,
                     const KnownCovariance& known, std::size_t batches) {
  const MatrixXd jacobian = sensitivity(system, first.scale, gmm.information_inverse, gmm.left,
                                        gmm.weight * gmm.residual, gmm.theta_scaled);
  const double factor = finite_sample_factor(batches, gmm.rank, system.a.cols());
  GmmErrors out;
  out.series = std::sqrt(factor) * deviations * jacobian.transpose();
  out.errors = with_known(long_run_covariance(out.series), jacobian * known * jacobian.transpose());
  return out;
}

}  // namespace momentid
