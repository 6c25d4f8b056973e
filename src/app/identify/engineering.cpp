// The identified model as engineers read it: linearised at its equilibrium, its natural
// frequencies and damping ratios, with standard errors by the delta method.

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "momentid/identify.hpp"
#include "momentid/simulate.hpp"

namespace momentid {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The right-hand side f(y) at the estimates `theta`, the inputs at `u`.
class RightHandSide {
 public:
  RightHandSide(const Model& model, const std::vector<double>& theta, std::vector<double> u)
      : f_(model, numbers(theta)), u_(std::move(u)), n_(f_.states()) {}
  VectorXd operator()(const VectorXd& y) const {
    VectorXd out(n_);
    if (!f_.derivative(y.data(), u_.data(), out.data())) out.setConstant(NAN);
    return out;
  }
  int states() const { return n_; }

 private:
  static std::vector<GiNaC::numeric> numbers(const std::vector<double>& theta) {
    std::vector<GiNaC::numeric> out;
    for (double v : theta) out.emplace_back(v);
    return out;
  }
  CompiledModel f_;
  std::vector<double> u_;
  int n_;
};

// The step of a difference in y: small against the states' spread, large against rounding.
constexpr double kStep = 1e-6;

// The Jacobian of f at y by central differences; `kink` names the first state in which f is not
// differentiable at y (an abs or sign switching there), or is -1: its one-sided derivatives
// differ (a kink), or its difference quotient halves as the step doubles (a jump).
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

// The modes of the linearisation at `theta`: (frequency in Hz, damping ratio) of each complex
// pair of eigenvalues, by frequency; `why` says why there are none.
std::vector<std::pair<double, double>> modes_at(const Model& model,
                                                const std::vector<double>& theta,
                                                const std::vector<double>& u, VectorXd& y,
                                                std::string& why) {
  const RightHandSide f(model, theta, u);
  y = VectorXd::Zero(f.states());
  // Newton from the origin to the equilibrium f(y) = 0.
  int kink = -1;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const VectorXd residual = f(y);
    if (!residual.allFinite()) break;
    if (residual.norm() <= 1e-12 * std::max(1.0, y.norm())) break;
    y -= jacobian(f, y, kink).fullPivLu().solve(residual);
  }
  const VectorXd residual = f(y);
  if (!residual.allFinite() || residual.norm() > 1e-8 * std::max(1.0, y.norm())) {
    why = "no equilibrium was found near the origin under the inputs' means";
    return {};
  }
  const MatrixXd a = jacobian(f, y, kink);
  if (kink >= 0) {
    why = "the model has no linearisation at its equilibrium: an abs(...) or sign(...) term " +
          std::string("switches there in ") + model.states()[static_cast<std::size_t>(kink)].name;
    return {};
  }
  const Eigen::VectorXcd lambda = Eigen::EigenSolver<MatrixXd>(a, false).eigenvalues();
  std::vector<std::pair<double, double>> out;
  for (const std::complex<double>& l : lambda) {
    if (l.imag() <= 0) continue;
    out.emplace_back(std::abs(l) / (2 * std::numbers::pi), -l.real() / std::abs(l));
  }
  std::sort(out.begin(), out.end());
  if (out.empty()) why = "the linearised model has no oscillating mode (its eigenvalues are real)";
  return out;
}

}  // namespace

LinearisedModes linearised_modes(const IdentifyResult& r) {
  LinearisedModes out;
  if (!r.estimate.usable()) {
    out.unavailable = "the estimate is not usable";
    return out;
  }
  const Model& model = *r.model;
  const std::vector<ParameterEstimate>& parameters = r.parameters();
  std::vector<double> theta;
  for (const ParameterEstimate& p : parameters) theta.push_back(p.estimate);
  std::vector<double> u;
  for (const Declaration& input : model.inputs()) {
    const auto it = std::find_if(r.means.begin(), r.means.end(),
                                 [&](const ChannelMean& m) { return m.name == input.name; });
    u.push_back(it == r.means.end() ? 0.0 : it->mean);
  }
  VectorXd y;
  const auto modes = modes_at(model, theta, u, y, out.unavailable);
  if (modes.empty()) return out;
  out.equilibrium.assign(y.data(), y.data() + y.size());
  // d (frequency, damping) / d theta_p by central differences, over the parameters with errors.
  const std::size_t count = parameters.size(), m = modes.size();
  MatrixXd gradient =
      MatrixXd::Zero(2 * static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(count));
  for (std::size_t p = 0; p < count; ++p) {
    const double se = parameters[p].std_error;
    if (!(se > 0)) continue;
    const double h = 1e-3 * se;
    std::vector<double> up = theta, down = theta;
    up[p] += h;
    down[p] -= h;
    VectorXd ignored;
    std::string why;
    const auto plus = modes_at(model, up, u, ignored, why);
    const auto minus = modes_at(model, down, u, ignored, why);
    if (plus.size() != m || minus.size() != m) continue;
    for (std::size_t k = 0; k < m; ++k) {
      gradient(2 * k, p) = (plus[k].first - minus[k].first) / (2 * h);
      gradient(2 * k + 1, p) = (plus[k].second - minus[k].second) / (2 * h);
    }
  }
  const Fit& fit = r.estimate.main();
  MatrixXd covariance =
      MatrixXd::Zero(static_cast<Eigen::Index>(count), static_cast<Eigen::Index>(count));
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t j = 0; j < count; ++j) {
      const double si = parameters[i].std_error, sj = parameters[j].std_error;
      if (!(si > 0 && sj > 0)) continue;
      const double rho = i == j ? 1.0 : fit.correlation.empty() ? 0.0 : fit.correlation[i][j];
      covariance(i, j) = std::isfinite(rho) ? rho * si * sj : 0.0;
    }
  }
  const MatrixXd errors = gradient * covariance * gradient.transpose();
  for (std::size_t k = 0; k < m; ++k) {
    out.modes.push_back({modes[k].first, std::sqrt(std::max(0.0, errors(2 * k, 2 * k))),
                         modes[k].second, std::sqrt(std::max(0.0, errors(2 * k + 1, 2 * k + 1)))});
  }
  return out;
}

}  // namespace momentid
