#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <tuple>
#include <utility>
#include <vector>

#include "momentid/estimate.hpp"

namespace momentid {

// Where one moment enters the system, entry by entry: d A / d mu_k and d b / d mu_k.
struct MomentUse {
  std::vector<std::tuple<Eigen::Index, Eigen::Index, double>> a;  // row, parameter, weight
  std::vector<std::pair<Eigen::Index, double>> b;                 // row, weight
};

// MomentRows at the estimated moments: A theta = b in numbers, with each moment's place in them,
// which the delta method differentiates. With weighted rows (SolveOptions::normalise_rows) A, b
// and the uses are those of the weighted rows, the weights taken as constants.
struct LinearSystem {
  Eigen::MatrixXd a;  // rows x parameters
  Eigen::VectorXd b;
  std::vector<MomentUse> uses;  // one per moment
};

// The contract of solve_rows: throws std::invalid_argument unless every row has one coefficient
// per parameter and a right-hand side, and every entry indexes one of `moments` estimates.
void check_shape(const MomentRows& rows, Eigen::Index parameters, std::size_t moments);

// `rows` (of the shape check_shape wants) at the moments' values `mean`, which the rows' entries
// index. `normalise_rows`: each row divided by the length of its coefficients (rows of zero
// coefficients as they are).
LinearSystem evaluate(const MomentRows& rows, Eigen::Index parameters,
                      const std::vector<double>& mean, bool normalise_rows);

// d g / d mu for the equations g = A theta - b at `theta` (unscaled): rows x moments, sparse
// (an equation reads few of the moments), so that the batch series of the equations costs the
// batches times the entries, whatever the number of moments.
Eigen::SparseMatrix<double> equations_jacobian(const LinearSystem& system,
                                               const Eigen::VectorXd& theta);

// The equations' batch series D g_mu(theta)' at any theta, from the moments' batch series D
// (batches x moments, batch_deviations). g_mu = sum_p theta_p G_p - G_b is linear in theta
// (G_p = d a_p / d mu, the p-th column's gradient), so the series are kept per column and
// summed: one product with the moments in all, not one per theta at which the weighting, its
// sensitivity and the J test read them (an equation of the lagged system reads a thousand
// moments, and there are thousands).
class EquationSeries {
 public:
  // Keeps a reference to `deviations`.
  EquationSeries(const LinearSystem& system, const Eigen::MatrixXd& deviations);
  // D g_mu(theta)' (batches x rows).
  Eigen::MatrixXd at(const Eigen::VectorXd& theta) const;
  // G_p (rows x moments) and D G_p'.
  const Eigen::SparseMatrix<double>& gradient(Eigen::Index p) const {
    return gradients_[static_cast<std::size_t>(p)];
  }
  const Eigen::MatrixXd& column(Eigen::Index p) const {
    return columns_[static_cast<std::size_t>(p)];
  }
  const Eigen::MatrixXd& deviations() const { return deviations_; }

 private:
  const Eigen::MatrixXd& deviations_;
  std::vector<Eigen::SparseMatrix<double>> gradients_;
  std::vector<Eigen::MatrixXd> columns_;
  Eigen::MatrixXd constant_;  // D G_b'
};

// A covariance of the moments' record means known from elsewhere (moments x moments, nonzero
// only over the few moments it concerns), and what it adds to the covariance of a series
// J mu: J K J'.
using KnownCovariance = Eigen::SparseMatrix<double>;

// The known covariance of independent moments with the variances `variance` (one per moment of
// `estimates`, or empty: none). Throws std::invalid_argument for another count.
KnownCovariance diagonal_covariance(const std::vector<double>& variance,
                                    const MomentEstimates& estimates);

}  // namespace momentid
