#include "solve/least_squares.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "solve/numbers.hpp"

namespace momentid {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// One null vector (scaled columns) as a combination of the parameters, its largest weight 1:
// "k - 2*c". Marks the parameters it touches as not identifiable.
std::string combination(const VectorXd& null, const VectorXd& scale,
                        const std::vector<std::string>& names, std::vector<bool>& identifiable) {
  VectorXd d = null.cwiseQuotient(scale);
  d /= d.cwiseAbs().maxCoeff();
  std::string combo;
  for (Index p = 0; p < null.size(); ++p) {
    if (std::abs(null(p)) < 1e-6) continue;
    identifiable[static_cast<std::size_t>(p)] = false;
    const double w = d(p);
    combo += (combo.empty() ? (w < 0 ? "-" : "") : (w < 0 ? " - " : " + ")) +
             (std::abs(std::abs(w) - 1) < 1e-9 ? "" : format_number(std::abs(w)) + "*") +
             names[static_cast<std::size_t>(p)];
  }
  return combo;
}

}  // namespace

LeastSquares least_squares(const LinearSystem& system) {
  const Index rows = system.a.rows(), params = system.a.cols();
  LeastSquares out;
  out.scale.resize(params);
  for (Index p = 0; p < params; ++p) {
    const double norm = system.a.col(p).norm();
    out.scale(p) = norm > 0 ? norm : 1;
  }
  out.scaled = system.a * out.scale.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<MatrixXd> svd(out.scaled, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const VectorXd& sigma = svd.singularValues();
  const double tolerance = 1e-10 * (sigma.size() > 0 ? sigma(0) : 0.0);
  for (Index i = 0; i < sigma.size(); ++i) out.rank += sigma(i) > tolerance ? 1 : 0;
  const Index smallest = std::min(rows, params) - 1;
  out.condition =
      sigma(smallest) > 0 ? sigma(0) / sigma(smallest) : std::numeric_limits<double>::infinity();
  if (out.rank == 0) return out;

  const MatrixXd u = svd.matrixU().leftCols(out.rank);
  const MatrixXd v = svd.matrixV().leftCols(out.rank);
  const VectorXd inverse_sigma = sigma.head(out.rank).cwiseInverse();
  out.null_space = svd.matrixV().rightCols(params - out.rank);
  out.pinv = v * inverse_sigma.asDiagonal() * u.transpose();
  out.normal_pinv = v * inverse_sigma.cwiseAbs2().asDiagonal() * v.transpose();
  out.theta_scaled = out.pinv * system.b;
  out.theta = out.theta_scaled.cwiseQuotient(out.scale);
  out.residual = system.b - out.scaled * out.theta_scaled;
  return out;
}

Identifiability identifiability(const LeastSquares& solution,
                                const std::vector<std::string>& names) {
  const Index params = solution.scale.size();
  Identifiability out{std::vector<bool>(static_cast<std::size_t>(params), true), ""};
  if (solution.rank >= params) return out;
  std::string combos;
  for (Index j = 0; j < solution.null_space.cols(); ++j) {
    combos += (combos.empty() ? "" : "; ") +
              combination(solution.null_space.col(j), solution.scale, names, out.identifiable);
  }
  // No direction to name when the equations hold values beyond doubles (an outlier's powers).
  out.message = "the data cannot separate the parameters" +
                (combos.empty() ? std::string() : " along " + combos) + ": only " +
                std::to_string(solution.rank) + " of " + std::to_string(params) +
                " parameter combinations are determined";
  return out;
}

}  // namespace momentid
