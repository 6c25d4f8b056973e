#include "solve/linear_system.hpp"

#include <stdexcept>
#include <string>

namespace momentid {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

void check_shape(const MomentRows& rows, Index parameters, std::size_t moments) {
  if (rows.b.size() != rows.a.size()) {
    throw std::invalid_argument("solve_rows: " + std::to_string(rows.a.size()) + " rows of " +
                                "coefficients for " + std::to_string(rows.b.size()) +
                                " right-hand sides");
  }
  const auto indexed = [&](const MomentRows::Entry& e) {
    for (const auto& [k, w] : e.moments) {
      if (k >= moments) {
        throw std::invalid_argument("solve_rows: an entry reads moment " + std::to_string(k) +
                                    " of " + std::to_string(moments) + " estimated");
      }
    }
  };
  for (std::size_t r = 0; r < rows.a.size(); ++r) {
    if (rows.a[r].size() != static_cast<std::size_t>(parameters)) {
      throw std::invalid_argument("solve_rows: row " + std::to_string(r) + " has " +
                                  std::to_string(rows.a[r].size()) + " coefficients for " +
                                  std::to_string(parameters) + " parameters");
    }
    for (const MomentRows::Entry& e : rows.a[r]) indexed(e);
    indexed(rows.b[r]);
  }
}

KnownCovariance diagonal_covariance(const std::vector<double>& variance,
                                    const MomentEstimates& estimates) {
  const auto k = static_cast<Index>(estimates.mean.size());
  KnownCovariance known(k, k);
  if (variance.empty()) return known;
  if (variance.size() != estimates.mean.size()) {
    throw std::invalid_argument("solve_rows: " + std::to_string(variance.size()) +
                                " moment variances for " + std::to_string(k) + " moments");
  }
  std::vector<Eigen::Triplet<double>> entries;
  for (Index i = 0; i < k; ++i) {
    if (variance[static_cast<std::size_t>(i)] > 0) {
      entries.emplace_back(i, i, variance[static_cast<std::size_t>(i)]);
    }
  }
  known.setFromTriplets(entries.begin(), entries.end());
  return known;
}

namespace {

// Each row divided by the length of its coefficients; the uses with it.
void normalise(LinearSystem& system) {
  const Index rows = system.a.rows();
  VectorXd weight = VectorXd::Ones(rows);
  for (Index r = 0; r < rows; ++r) {
    if (const double norm = system.a.row(r).norm(); norm > 0) weight(r) = 1 / norm;
  }
  system.a = weight.asDiagonal() * system.a;
  system.b = system.b.cwiseProduct(weight);
  for (MomentUse& use : system.uses) {
    for (auto& [r, p, w] : use.a) w *= weight(r);
    for (auto& [r, w] : use.b) w *= weight(r);
  }
}

}  // namespace

LinearSystem evaluate(const MomentRows& rows, Index parameters, const std::vector<double>& mean,
                      bool normalise_rows) {
  const auto count = static_cast<Index>(rows.a.size());
  LinearSystem out{MatrixXd::Zero(count, parameters), VectorXd::Zero(count),
                   std::vector<MomentUse>(mean.size())};
  const auto add = [&](const MomentRows::Entry& e, double& into, auto&& use) {
    into += e.constant;
    for (const auto& [k, w] : e.moments) {
      into += w * mean[k];
      use(k, w);
    }
  };
  for (Index r = 0; r < count; ++r) {
    const auto& row = rows.a[static_cast<std::size_t>(r)];
    for (Index p = 0; p < parameters; ++p) {
      add(row[static_cast<std::size_t>(p)], out.a(r, p),
          [&](std::size_t k, double w) { out.uses[k].a.emplace_back(r, p, w); });
    }
    add(rows.b[static_cast<std::size_t>(r)], out.b(r),
        [&](std::size_t k, double w) { out.uses[k].b.emplace_back(r, w); });
  }
  if (normalise_rows) normalise(out);
  return out;
}

Eigen::SparseMatrix<double> equations_jacobian(const LinearSystem& system, const VectorXd& theta) {
  const auto moments = static_cast<Index>(system.uses.size());
  std::vector<Eigen::Triplet<double>> entries;
  for (Index k = 0; k < moments; ++k) {
    const MomentUse& use = system.uses[static_cast<std::size_t>(k)];
    for (const auto& [r, p, w] : use.a) entries.emplace_back(r, k, w * theta(p));
    for (const auto& [r, w] : use.b) entries.emplace_back(r, k, -w);
  }
  Eigen::SparseMatrix<double> g_mu(system.a.rows(), moments);
  g_mu.setFromTriplets(entries.begin(), entries.end());  // duplicates summed
  return g_mu;
}

EquationSeries::EquationSeries(const LinearSystem& system, const MatrixXd& deviations)
    : deviations_(deviations) {
  const Index rows = system.a.rows(), moments = static_cast<Index>(system.uses.size());
  std::vector<std::vector<Eigen::Triplet<double>>> entries(
      static_cast<std::size_t>(system.a.cols()));
  std::vector<Eigen::Triplet<double>> constant;
  for (Index k = 0; k < moments; ++k) {
    const MomentUse& use = system.uses[static_cast<std::size_t>(k)];
    for (const auto& [r, p, w] : use.a) entries[static_cast<std::size_t>(p)].emplace_back(r, k, w);
    for (const auto& [r, w] : use.b) constant.emplace_back(r, k, w);
  }
  for (const auto& column : entries) {
    gradients_.emplace_back(rows, moments);
    gradients_.back().setFromTriplets(column.begin(), column.end());
    columns_.push_back(deviations * gradients_.back().transpose());
  }
  Eigen::SparseMatrix<double> g_b(rows, moments);
  g_b.setFromTriplets(constant.begin(), constant.end());
  constant_ = deviations * g_b.transpose();
}

MatrixXd EquationSeries::at(const VectorXd& theta) const {
  MatrixXd out = -constant_;
  for (std::size_t p = 0; p < columns_.size(); ++p) {
    out += theta(static_cast<Index>(p)) * columns_[p];
  }
  return out;
}

}  // namespace momentid
