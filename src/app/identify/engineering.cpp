// The identified model as engineers read it: linearised at its equilibrium, its natural
// frequencies and damping ratios, with standard errors by the delta method.

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <optional>

#include "app/identify/linearise.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/error.hpp"
#include "momentid/identify.hpp"
#include "momentid/simulate.hpp"

namespace momentid {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The modes of the linearisation at `theta`: (frequency in Hz, damping ratio) of each complex
// pair of eigenvalues, by frequency; `why` says why there are none.
std::vector<std::pair<double, double>> modes_at(const Model& model,
                                                const std::vector<double>& theta,
                                                const std::vector<double>& u, VectorXd& y,
                                                std::string& why) {
  const RightHandSide f(model, theta, u);
  const std::optional<VectorXd> at = equilibrium(f);
  if (!at) {
    why = "no equilibrium was found near the origin under the inputs' means";
    return {};
  }
  y = *at;
  int kink = -1;
  const MatrixXd a = jacobian(f, y, kink);
  if (kink >= 0 && !model.functions().empty()) {
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

// The standard errors of values(theta) at the estimates by the delta method: derivatives by
// central differences over the parameters that have an error (a thousandth of it, or of the
// estimate when that is larger than a ten-thousandth of it), with the main fit's covariance.
// NaN where values(theta) cannot be evaluated at a perturbed theta (it returns another count)
// or the covariance is unknown.
template <typename Values>
VectorXd delta_errors(const IdentifyResult& r, const Values& values) {
  const std::vector<ParameterEstimate>& parameters = r.parameters();
  const std::vector<double> theta = estimates_of(r);
  const VectorXd at = values(theta);
  const auto count = static_cast<Eigen::Index>(parameters.size());
  const std::vector<std::vector<double>> cov = r.estimate.main().covariance();
  MatrixXd gradient = MatrixXd::Zero(at.size(), count), covariance(count, count);
  for (Eigen::Index i = 0; i < count; ++i) {
    for (Eigen::Index j = 0; j < count; ++j) {
      covariance(i, j) = cov[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
    }
  }
  for (Eigen::Index p = 0; p < count; ++p) {
    const auto q = static_cast<std::size_t>(p);
    const double se = parameters[q].std_error;
    if (!(se > 0)) continue;
    const double h = std::max(1e-3 * se, 1e-7 * std::abs(theta[q]));
    std::vector<double> up = theta, down = theta;
    up[q] += h;
    down[q] -= h;
    const VectorXd plus = values(up), minus = values(down);
    if (plus.size() != at.size() || minus.size() != at.size()) {
      return VectorXd::Constant(at.size(), NAN);
    }
    gradient.col(p) = (plus - minus) / (2 * h);
  }
  if (!covariance.allFinite()) return VectorXd::Constant(at.size(), NAN);
  return (gradient * covariance * gradient.transpose()).diagonal().cwiseMax(0).cwiseSqrt();
}

// The mass m of an oscillator y' = v, m v' = -R(y) - D(v) + ...: the constant coefficient of v'
// in the equation that holds it, at `theta`; NaN when there is none.
double mass_of(const Model& model, const std::vector<double>& theta) {
  double m = 0;
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      if (t.derivative != 1) continue;
      if (std::any_of(t.monomial.begin(), t.monomial.end(), [](int e) { return e != 0; })) {
        return NAN;
      }
      m += t.coefficient.to_double() *
           (t.parameter >= 0 ? theta[static_cast<std::size_t>(t.parameter)] : 1.0);
    }
  }
  return m != 0 ? m : NAN;
}

LinearisedModes modes_of(const IdentifyResult& r) {
  LinearisedModes out;
  if (!r.estimate.usable()) {
    out.unavailable = "the estimate is not usable";
    return out;
  }
  const Model& model = *r.model;
  const std::vector<double> u = input_means(r);
  VectorXd y;
  const auto modes = modes_at(model, estimates_of(r), u, y, out.unavailable);
  if (modes.empty()) return out;
  out.equilibrium.assign(y.data(), y.data() + y.size());
  // Frequency and damping of each mode, in turn.
  const auto values = [&](const std::vector<double>& theta) {
    VectorXd ignored;
    std::string why;
    const auto at = modes_at(model, theta, u, ignored, why);
    VectorXd v(2 * static_cast<Eigen::Index>(at.size()));
    for (std::size_t k = 0; k < at.size(); ++k) {
      v(static_cast<Eigen::Index>(2 * k)) = at[k].first;
      v(static_cast<Eigen::Index>(2 * k + 1)) = at[k].second;
    }
    return v;
  };
  const VectorXd errors = delta_errors(r, values);
  for (std::size_t k = 0; k < modes.size(); ++k) {
    out.modes.push_back({modes[k].first, errors(static_cast<Eigen::Index>(2 * k)), modes[k].second,
                         errors(static_cast<Eigen::Index>(2 * k + 1))});
  }
  return out;
}

// Whether the model's first equation is y' = v (the second state's value), at `theta`.
bool kinematic(const Model& model, const std::vector<double>& theta, const std::vector<double>& u) {
  const RightHandSide f(model, theta, u);
  for (const auto& [y, v] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {-2.0, 3.0}}) {
    if (f(Eigen::Vector2d(y, v))(0) != v) return false;
  }
  return true;
}

// The restoring force R at each displacement, m times minus the acceleration at rest without
// inputs, and the backbone: omega(A)^2 = 1 / (pi m A) int_0^2pi (R(y0 + A cos p) - R(y0)) cos p dp
// (harmonic balance) at each amplitude, as frequencies in Hz (NaN where omega^2 <= 0).
VectorXd curves_at(const Model& model, const std::vector<double>& theta, double y0,
                   const std::vector<double>& displacements,
                   const std::vector<double>& amplitudes) {
  const double m = mass_of(model, theta);
  const RightHandSide f(model, theta, std::vector<double>(model.inputs().size(), 0.0));
  const auto force = [&](double y) { return -m * f(Eigen::Vector2d(y, 0))(1); };
  VectorXd out(static_cast<Eigen::Index>(displacements.size() + amplitudes.size()));
  Eigen::Index i = 0;
  for (double y : displacements) out(i++) = force(y);
  constexpr int kPhases = 64;  // exact for the cosine series of polynomials up to degree 63
  for (double a : amplitudes) {
    double sum = 0;
    for (int k = 0; k < kPhases; ++k) {
      const double phase = 2 * std::numbers::pi * k / kPhases;
      sum += (force(y0 + a * std::cos(phase)) - force(y0)) * std::cos(phase);
    }
    const double omega2 = sum * 2 / kPhases / (m * a);
    out(i++) = omega2 > 0 ? std::sqrt(omega2) / (2 * std::numbers::pi) : NAN;
  }
  return out;
}

NonlinearCurves curves_of(const IdentifyResult& r) {
  NonlinearCurves out;
  const Model& model = *r.model;
  const std::vector<double> theta = estimates_of(r);
  const ChannelStatistics* channel =
      model.states().size() == 2 ? r.data.channel(model.states()[0].name) : nullptr;
  if (!r.estimate.usable() || !channel || !kinematic(model, theta, input_means(r)) ||
      !std::isfinite(mass_of(model, theta))) {
    out.unavailable =
        "the curves are drawn for an oscillator y' = v, m v' = ... with a constant mass, a usable "
        "estimate and a column for y";
    return out;
  }
  const LinearisedModes linear = linearised_modes(r);
  const double y0 = linear.equilibrium.empty() ? 0.0 : linear.equilibrium[0];
  // To 4 digits: the grid does not depend on how the pass summed (threads, processes).
  const auto rounded = [](double x) {
    char text[32];
    std::snprintf(text, sizeof text, "%.4g", x);
    return std::strtod(text, nullptr);
  };
  const double spread = rounded(std::sqrt(channel->variance)), mean = rounded(channel->mean);
  if (!(spread > 0)) {
    out.unavailable = "the record's displacement does not vary";
    return out;
  }
  out.state = model.states()[0].name;
  constexpr int kPoints = 41;
  for (int k = 0; k < kPoints; ++k) {
    out.displacement.push_back(mean + spread * (-3 + 6.0 * k / (kPoints - 1)));
    if (k > 0 && k % 2 == 0) out.amplitude.push_back(3 * spread * k / (kPoints - 1));
  }
  const auto values = [&](const std::vector<double>& t) {
    return curves_at(model, t, y0, out.displacement, out.amplitude);
  };
  const VectorXd at = values(theta), errors = delta_errors(r, values);
  const auto n = static_cast<Eigen::Index>(out.displacement.size());
  for (Eigen::Index i = 0; i < at.size(); ++i) {
    (i < n ? out.force : out.frequency_hz).push_back(at(i));
    (i < n ? out.force_se : out.frequency_se).push_back(errors(i));
  }
  return out;
}

// A model that cannot be solved for its derivatives (algebraic equations, a singular mass)
// has no linearisation or curves: said in `unavailable`, not thrown, for the report stands
// without them.
template <typename Result, typename Compute>
Result or_unavailable(const Compute& compute) {
  try {
    return compute();
  } catch (const Error& e) {
    Result out;
    out.unavailable = e.what();
    return out;
  }
}

// The gains of mean_response: -A^-1 B of the linearisation at the origin, the inputs' columns
// of B by central differences of a step of each input's standard deviation.
std::optional<MatrixXd> mean_gains(const IdentifyResult& r) {
  const Model& model = *r.model;
  const std::size_t inputs = model.inputs().size();
  const RightHandSide f(model, estimates_of(r), std::vector<double>(inputs, 0.0));
  const VectorXd origin = VectorXd::Zero(f.states());
  int kink = -1;
  const MatrixXd a = jacobian(f, origin, kink);
  if (kink >= 0 || !a.allFinite()) return std::nullopt;
  MatrixXd b(f.states(), static_cast<Eigen::Index>(inputs));
  for (std::size_t j = 0; j < inputs; ++j) {
    const double spread = spread_of(r, model.inputs()[j].name);
    const double h = spread > 0 ? spread : 1.0;
    std::vector<double> up(inputs, 0.0), down(inputs, 0.0);
    up[j] = h;
    down[j] = -h;
    b.col(static_cast<Eigen::Index>(j)) = (f.at(origin, up) - f.at(origin, down)) / (2 * h);
  }
  const Eigen::FullPivLU<MatrixXd> lu(a);
  if (!lu.isInvertible() || !b.allFinite()) return std::nullopt;
  return MatrixXd(-lu.solve(b));
}

}  // namespace

MeanResponse mean_response(const IdentifyResult& r) {
  MeanResponse out;
  if (!r.estimate.usable() || r.model->inputs().empty()) return out;
  const AlgebraLock lock;
  std::optional<MatrixXd> gains;
  try {
    gains = mean_gains(r);
  } catch (const Error&) {
    return out;  // the estimates make no model to evaluate
  }
  if (!gains) return out;
  const std::vector<double> u = input_means(r);
  for (Eigen::Index s = 0; s < gains->rows(); ++s) {
    std::vector<double> row;
    double mean = 0;
    for (Eigen::Index j = 0; j < gains->cols(); ++j) {
      row.push_back((*gains)(s, j));
      mean += row.back() * u[static_cast<std::size_t>(j)];
    }
    out.mean.push_back(mean);
    out.gain.push_back(std::move(row));
  }
  return out;
}

LinearisedModes linearised_modes(const IdentifyResult& r) {
  const AlgebraLock lock;
  return or_unavailable<LinearisedModes>([&] { return modes_of(r); });
}

NonlinearCurves nonlinear_curves(const IdentifyResult& r) {
  const AlgebraLock lock;
  return or_unavailable<NonlinearCurves>([&] { return curves_of(r); });
}

}  // namespace momentid
