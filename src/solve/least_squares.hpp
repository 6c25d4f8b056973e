#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "solve/linear_system.hpp"

namespace momentid {

// The least-squares solution of A theta = b. The columns are scaled to unit length, because
// moments of different orders differ by orders of magnitude, and solved by a rank-revealing SVD:
// where the rank falls short the solution is the minimum-norm one (in scaled columns).
struct LeastSquares {
  Eigen::VectorXd scale;   // each column's length (1 for a zero column)
  Eigen::MatrixXd scaled;  // A with its columns divided by `scale`
  // Singular values above 1e-10 of the largest; the condition number of `scaled`, largest over
  // smallest singular value (infinite when the smallest is 0).
  Eigen::Index rank = 0;
  double condition = 0;
  // The rest only for rank > 0, in scaled columns but `theta`:
  Eigen::MatrixXd null_space;         // right singular vectors beyond the rank
  Eigen::MatrixXd pinv, normal_pinv;  // scaled^+ (parameters x rows), (scaled' scaled)^+
  Eigen::VectorXd theta_scaled, theta;
  Eigen::VectorXd residual;  // b - A theta
};

LeastSquares least_squares(const LinearSystem& system);

// What a rank-deficient solution leaves undetermined: the parameters the null space touches,
// which cannot be told apart from others, and the combinations along which the data cannot
// separate them, as a status message naming the parameters `names` (empty at full rank).
struct Identifiability {
  std::vector<bool> identifiable;
  std::string message;
};
Identifiability identifiability(const LeastSquares& solution,
                                const std::vector<std::string>& names);

}  // namespace momentid
