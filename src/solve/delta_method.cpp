#include "solve/delta_method.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "solve/numbers.hpp"

namespace momentid {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

MatrixXd batch_deviations(const MomentEstimates& estimates) {
  const auto b = static_cast<Index>(estimates.batch_means.size());
  const auto k = static_cast<Index>(estimates.mean.size());
  VectorXd length = VectorXd::Ones(b);
  for (Index i = 0; i < b; ++i) {
    const auto row = static_cast<std::size_t>(i);
    if (estimates.batch_means[row].size() != estimates.mean.size()) {
      throw std::invalid_argument("estimates: batch " + std::to_string(row) + " has " +
                                  std::to_string(estimates.batch_means[row].size()) +
                                  " means for " + std::to_string(k) + " moments");
    }
    if (!estimates.batch_intervals.empty()) {
      length(i) = static_cast<double>(estimates.batch_intervals[row]);
    }
  }
  MatrixXd out(b, k);
  if (b == 0) return out;
  length /= length.mean();
  // The batch means are stored batch by batch and the series go down columns: the means are
  // summed along the batches' rows, and the series filled in tiles small enough for the cache
  // (the lagged equations read thousands of moments over a thousand batches).
  std::vector<double> mean(static_cast<std::size_t>(k), 0.0);
  for (Index i = 0; i < b; ++i) {
    const std::vector<double>& row = estimates.batch_means[static_cast<std::size_t>(i)];
    for (std::size_t j = 0; j < mean.size(); ++j) mean[j] += length(i) * row[j];
  }
  for (double& m : mean) m /= static_cast<double>(b);
  constexpr Index kTile = 64;
  for (Index i0 = 0; i0 < b; i0 += kTile) {
    const Index i1 = std::min(b, i0 + kTile);
    for (Index j = 0; j < k; ++j) {
      const auto column = static_cast<std::size_t>(j);
      for (Index i = i0; i < i1; ++i) {
        out(i, j) =
            length(i) * (estimates.batch_means[static_cast<std::size_t>(i)][column] - mean[column]);
      }
    }
  }
  return out;
}

MatrixXd sensitivity(const LinearSystem& system, const VectorXd& scale,
                     const MatrixXd& normal_inverse, const MatrixXd& left,
                     const VectorXd& weighted_residual, const VectorXd& at) {
  // Column k: N^-1 (dA_k' W r) - N^-1 A' W dg_k with dg_k = dA_k theta - db_k, the second term
  // for all moments at once from the sparse d g / d mu.
  const Index params = system.a.cols();
  const auto moments = static_cast<Index>(system.uses.size());
  std::vector<Eigen::Triplet<double>> entries;
  for (Index k = 0; k < moments; ++k) {
    for (const auto& [r, p, w] : system.uses[static_cast<std::size_t>(k)].a) {
      entries.emplace_back(p, k, w / scale(p) * weighted_residual(r));
    }
  }
  Eigen::SparseMatrix<double> residual_part(params, moments);
  residual_part.setFromTriplets(entries.begin(), entries.end());
  const VectorXd theta = at.cwiseQuotient(scale);
  const MatrixXd jacobian =
      normal_inverse * residual_part - left * equations_jacobian(system, theta);
  return scale.cwiseInverse().asDiagonal() * jacobian;
}

LongRunCovariance with_known(LongRunCovariance errors, const MatrixXd& added) {
  if (added.isZero(0)) return errors;
  double dof = std::numeric_limits<double>::infinity();
  for (Index i = 0; i < added.rows(); ++i) {
    const double series = errors.covariance(i, i), total = series + added(i, i);
    if (series > 0) dof = std::min(dof, errors.dof * (total / series) * (total / series));
  }
  errors.covariance += added;
  errors.linear += added;
  if (std::isfinite(dof)) errors.dof = dof;
  return errors;
}

std::vector<std::vector<double>> correlation_of(const MatrixXd& cov,
                                                const std::vector<bool>& identifiable) {
  const auto n = static_cast<std::size_t>(cov.rows());
  std::vector<std::vector<double>> out(n, std::vector<double>(n, kNaN));
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      const auto a = static_cast<Index>(i), b = static_cast<Index>(j);
      const double scale = std::sqrt(cov(a, a) * cov(b, b));
      // Symmetric to the last bit, whatever the rounding of the products that made cov.
      if (identifiable[i] && identifiable[j] && scale > 0) {
        out[i][j] = (cov(a, b) + cov(b, a)) / 2 / scale;
      }
    }
  }
  return out;
}

std::vector<std::vector<double>> rows_of(const MatrixXd& matrix) {
  std::vector<std::vector<double>> out(static_cast<std::size_t>(matrix.rows()));
  for (Index b = 0; b < matrix.rows(); ++b) {
    for (Index p = 0; p < matrix.cols(); ++p) {
      out[static_cast<std::size_t>(b)].push_back(matrix(b, p));
    }
  }
  return out;
}

MatrixXd matrix_of(const std::vector<std::vector<double>>& rows, Index columns) {
  MatrixXd out(static_cast<Index>(rows.size()), columns);
  for (Index i = 0; i < out.rows(); ++i) {
    for (Index j = 0; j < columns; ++j) {
      out(i, j) = rows[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
    }
  }
  return out;
}

void set_error(ParameterEstimate& estimate, double std_error, double t975) {
  estimate.std_error = std_error;
  estimate.ci_low = estimate.estimate - t975 * std_error;
  estimate.ci_high = estimate.estimate + t975 * std_error;
}

void warn_about_errors(Estimate& out, const LongRunCovariance& errors) {
  if (errors.order == 0 && out.batches >= 2) {
    out.warnings.push_back("only " + std::to_string(out.batches) +
                           " batches: the standard errors take the batch means as independent, "
                           "which overstates them for records without noise (use a longer record "
                           "or more batches)");
  }
}

}  // namespace momentid
