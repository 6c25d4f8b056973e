#include "solve/gmm.hpp"

#include <cmath>

#include "solve/delta_method.hpp"
#include "solve/long_run.hpp"

namespace momentid {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

OptimalWeighting optimal_weighting(const LinearSystem& system, const LeastSquares& first,
                                   const MatrixXd& deviations, const KnownCovariance& known,
                                   const VectorXd& at) {
  const Index rows = system.a.rows(), params = system.a.cols();
  const Eigen::SparseMatrix<double> g_mu = equations_jacobian(system, at);
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

IteratedWeighting iterated_weighting(const LinearSystem& system, const LeastSquares& first,
                                     const MatrixXd& deviations, const KnownCovariance& known,
                                     bool twice) {
  IteratedWeighting out;
  out.pilot = optimal_weighting(system, first, deviations, known, first.theta);
  out.weighted =
      twice ? optimal_weighting(system, first, deviations, known, out.pilot.theta) : out.pilot;
  return out;
}

double finite_sample_factor(std::size_t batches, Index equations, Index parameters) {
  const auto n = static_cast<double>(batches - 1);
  const auto m = static_cast<double>(equations);
  const auto q = static_cast<double>(parameters);
  return n * (n - 1) / ((n - m + q) * (n - m + q - 1));
}

namespace {

// d theta / d mu of a weighted estimate, its weights held.
MatrixXd sensitivity_of(const LinearSystem& system, const LeastSquares& first,
                        const OptimalWeighting& gmm) {
  return sensitivity(system, first.scale, gmm.information_inverse, gmm.left,
                     gmm.weight * gmm.residual, gmm.theta_scaled);
}

// d a_p / d mu for each column p of A: how it moves with the moments (rows x moments).
std::vector<Eigen::SparseMatrix<double>> column_jacobians(const LinearSystem& system) {
  std::vector<std::vector<Eigen::Triplet<double>>> entries(
      static_cast<std::size_t>(system.a.cols()));
  for (std::size_t k = 0; k < system.uses.size(); ++k) {
    for (const auto& [r, q, w] : system.uses[k].a) {
      entries[static_cast<std::size_t>(q)].emplace_back(r, static_cast<Index>(k), w);
    }
  }
  std::vector<Eigen::SparseMatrix<double>> out;
  for (const auto& column : entries) {
    out.emplace_back(system.a.rows(), static_cast<Index>(system.uses.size()));
    out.back().setFromTriplets(column.begin(), column.end());
  }
  return out;
}

MatrixXd centred(const MatrixXd& x) { return x.rowwise() - x.colwise().mean(); }

// d theta / d theta_at (unscaled), for weights W = S(theta_at)^-1: column j is
// N^-1 A' W (dS / d theta_j) W g at the estimate, g = A theta - b. S(theta) = sum_k G x_k x_k' G'
// / (B (B - 1)) + G K G' over the centred batch deviations x_k is quadratic in theta through
// G = d g / d mu, whose derivative in theta_j is d a_j / d mu.
MatrixXd weight_sensitivity(const LinearSystem& system, const LeastSquares& first,
                            const OptimalWeighting& gmm, const MatrixXd& deviations,
                            const KnownCovariance& known, const VectorXd& at) {
  const auto b = static_cast<double>(deviations.rows());
  const Eigen::SparseMatrix<double> g_mu = equations_jacobian(system, at);
  const MatrixXd u = centred(deviations * g_mu.transpose());
  const VectorXd h = -(gmm.weight * gmm.residual);  // W g
  const VectorXd uh = u * h;
  const VectorXd known_h = known * (g_mu.transpose() * h);
  const std::vector<Eigen::SparseMatrix<double>> columns = column_jacobians(system);
  MatrixXd out(system.a.cols(), system.a.cols());
  for (Index j = 0; j < system.a.cols(); ++j) {
    const Eigen::SparseMatrix<double>& g_j = columns[static_cast<std::size_t>(j)];
    const MatrixXd a_j = centred(deviations * g_j.transpose());
    const VectorXd ds_h = (a_j.transpose() * uh + u.transpose() * (a_j * h)) / (b * (b - 1)) +
                          g_j * known_h + g_mu * (known * (g_j.transpose() * h));
    out.col(j) = (gmm.left * ds_h).cwiseQuotient(first.scale);
  }
  return out;
}

}  // namespace

GmmErrors gmm_errors(const LinearSystem& system, const LeastSquares& first,
                     const OptimalWeighting& gmm, const MatrixXd& deviations,
                     const KnownCovariance& known, std::size_t batches,
                     const OptimalWeighting* pilot) {
  const double root = std::sqrt(finite_sample_factor(batches, gmm.rank, system.a.cols()));
  const MatrixXd jacobian = sensitivity_of(system, first, gmm);
  GmmErrors out;
  out.series = root * deviations * jacobian.transpose();
  MatrixXd corrected = out.series;
  if (pilot) {
    const MatrixXd through_weights =
        weight_sensitivity(system, first, gmm, deviations, known, pilot->theta) *
        sensitivity_of(system, first, *pilot);
    corrected += root * deviations * through_weights.transpose();
  }
  out.errors = with_known(long_run_covariance(corrected), jacobian * known * jacobian.transpose());
  return out;
}

}  // namespace momentid
