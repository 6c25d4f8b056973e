#include "solve/gmm.hpp"

#include <cmath>

#include "solve/delta_method.hpp"
#include "solve/long_run.hpp"

namespace momentid {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

MatrixXd known_part(const LinearSystem& system, const KnownCovariance& known, const VectorXd& at) {
  const Index rows = system.a.rows();
  if (known.nonZeros() == 0) return MatrixXd::Zero(rows, rows);
  const Eigen::SparseMatrix<double> g_mu = equations_jacobian(system, at);
  return MatrixXd(g_mu * known * g_mu.transpose());
}

OptimalWeighting optimal_weighting(const LinearSystem& system, const LeastSquares& first,
                                   const EquationSeries& series, const KnownCovariance& known,
                                   const VectorXd& at) {
  const Index rows = system.a.rows(), params = system.a.cols();
  const MatrixXd s = batch_covariance(series.at(at)) + known_part(system, known, at);
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
                                     const EquationSeries& series, const KnownCovariance& known,
                                     bool twice) {
  IteratedWeighting out;
  out.pilot = optimal_weighting(system, first, series, known, first.theta);
  out.weighted =
      twice ? optimal_weighting(system, first, series, known, out.pilot.theta) : out.pilot;
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

MatrixXd centred(const MatrixXd& x) { return x.rowwise() - x.colwise().mean(); }

// d theta / d theta_at (unscaled), for weights W = S(theta_at)^-1: column j is
// N^-1 A' W (dS / d theta_j) W g at the estimate, g = A theta - b. S(theta) = sum_k G x_k x_k' G'
// / (B (B - 1)) + G K G' over the centred batch deviations x_k is quadratic in theta through
// G = d g / d mu, whose derivative in theta_j is d a_j / d mu.
MatrixXd weight_sensitivity(const LinearSystem& system, const LeastSquares& first,
                            const OptimalWeighting& gmm, const EquationSeries& series,
                            const KnownCovariance& known, const VectorXd& at) {
  const auto b = static_cast<double>(series.deviations().rows());
  const MatrixXd u = centred(series.at(at));
  const VectorXd h = -(gmm.weight * gmm.residual);  // W g
  const VectorXd uh = u * h;
  const bool has_known = known.nonZeros() > 0;
  const Eigen::SparseMatrix<double> g_mu =
      has_known ? equations_jacobian(system, at) : Eigen::SparseMatrix<double>();
  const VectorXd known_h = has_known ? VectorXd(known * (g_mu.transpose() * h)) : VectorXd();
  MatrixXd out(system.a.cols(), system.a.cols());
  for (Index j = 0; j < system.a.cols(); ++j) {
    const MatrixXd a_j = centred(series.column(j));
    VectorXd ds_h = (a_j.transpose() * uh + u.transpose() * (a_j * h)) / (b * (b - 1));
    if (has_known) {
      const Eigen::SparseMatrix<double>& g_j = series.gradient(j);
      ds_h += g_j * known_h + g_mu * (known * (g_j.transpose() * h));
    }
    out.col(j) = (gmm.left * ds_h).cwiseQuotient(first.scale);
  }
  return out;
}

}  // namespace

GmmErrors gmm_errors(const LinearSystem& system, const LeastSquares& first,
                     const OptimalWeighting& gmm, const EquationSeries& series,
                     const KnownCovariance& known, std::size_t batches,
                     const OptimalWeighting* pilot) {
  const MatrixXd& deviations = series.deviations();
  const double root = std::sqrt(finite_sample_factor(batches, gmm.rank, system.a.cols()));
  const MatrixXd jacobian = sensitivity_of(system, first, gmm);
  GmmErrors out;
  out.series = root * deviations * jacobian.transpose();
  MatrixXd corrected = out.series;
  if (pilot) {
    const MatrixXd through_weights =
        weight_sensitivity(system, first, gmm, series, known, pilot->theta) *
        sensitivity_of(system, first, *pilot);
    corrected += root * deviations * through_weights.transpose();
  }
  out.errors = with_known(long_run_covariance(corrected), jacobian * known * jacobian.transpose());
  return out;
}

}  // namespace momentid
