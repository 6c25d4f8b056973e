#include "app/identify/linearise.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace momentid {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

// The step of a difference in y: small against the states' spread, large against rounding.
constexpr double kStep = 1e-6;

}  // namespace

MatrixXd jacobian(const RightHandSide& f, const VectorXd& y, int& kink) {
  const int n = f.states();
  MatrixXd out(n, n);
  const VectorXd at = f(y);
  kink = -1;
  for (int j = 0; j < n; ++j) {
    const double h = kStep * std::max(1.0, std::abs(y(j)));
    const auto at_offset = [&](double d) {
      VectorXd shifted = y;
      shifted(j) += d;
      return f(shifted);
    };
    const VectorXd forward = (at_offset(h) - at) / h, backward = (at - at_offset(-h)) / h;
    const VectorXd central = (forward + backward) / 2;
    const VectorXd wide = (at_offset(2 * h) - at_offset(-2 * h)) / (4 * h);
    const double scale = std::max({forward.cwiseAbs().maxCoeff(), backward.cwiseAbs().maxCoeff(),
                                   wide.cwiseAbs().maxCoeff(), 1e-300});
    const double mismatch = std::max((forward - backward).cwiseAbs().maxCoeff(),
                                     (central - wide).cwiseAbs().maxCoeff());
    if (kink < 0 && mismatch > 1e-3 * scale) kink = j;
    out.col(j) = central;
  }
  return out;
}

std::optional<VectorXd> equilibrium(const RightHandSide& f) {
  VectorXd y = VectorXd::Zero(f.states());
  int kink = -1;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const VectorXd residual = f(y);
    if (!residual.allFinite()) break;
    if (residual.norm() <= 1e-12 * std::max(1.0, y.norm())) break;
    y -= jacobian(f, y, kink).fullPivLu().solve(residual);
  }
  const VectorXd residual = f(y);
  if (!residual.allFinite() || residual.norm() > 1e-8 * std::max(1.0, y.norm())) {
    return std::nullopt;
  }
  return y;
}

double spread_of(const IdentifyResult& r, const std::string& name) {
  const ChannelStatistics* c = r.data.channel(name);
  return c && c->variance > 0 ? std::sqrt(c->variance) : 0;
}

std::vector<double> estimates_of(const IdentifyResult& r) {
  std::vector<double> out;
  for (const ParameterEstimate& p : r.parameters()) out.push_back(p.estimate);
  return out;
}

std::vector<double> input_means(const IdentifyResult& r) {
  std::vector<double> out;
  for (const Declaration& input : r.model->inputs()) {
    const auto it = std::find_if(r.means.begin(), r.means.end(),
                                 [&](const ChannelMean& m) { return m.name == input.name; });
    out.push_back(it == r.means.end() ? 0.0 : it->mean);
  }
  return out;
}

}  // namespace momentid
