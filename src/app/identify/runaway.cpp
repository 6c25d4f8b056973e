// Whether the identified model runs away from its equilibrium (identify.hpp, Runaway).

#include <algorithm>
#include <boost/numeric/odeint.hpp>
#include <cmath>
#include <numbers>

#include "app/identify/linearise.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/error.hpp"
#include "momentid/identify.hpp"

namespace momentid {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Runaway (identify.hpp): the start and the bound of the free response, in standard deviations of
// the measured states, and the longest it is followed, in steps.
constexpr double kRunawayStart = 1e-3, kRunawayBound = 1e3;
constexpr long kRunawaySteps = 200'000;

std::optional<Runaway> runaway_of(const IdentifyResult& r) {
  const Model& model = *r.model;
  const RightHandSide f(model, estimates_of(r), input_means(r));
  const std::optional<VectorXd> y0 = equilibrium(f);
  if (!y0) return std::nullopt;
  int kink = -1;
  const MatrixXd a = jacobian(f, *y0, kink);
  if ((kink >= 0 && !model.functions().empty()) || !a.allFinite()) return std::nullopt;
  const Eigen::EigenSolver<MatrixXd> eigen(a);
  const Eigen::VectorXcd lambda = eigen.eigenvalues();
  Eigen::Index fastest = 0, growing = 0;
  lambda.real().maxCoeff(&growing);
  lambda.cwiseAbs().maxCoeff(&fastest);
  const double sigma = lambda(growing).real();
  if (!(sigma > 0)) return std::nullopt;
  // The scale of each state: its standard deviation where the record has it.
  VectorXd scale(f.states());
  for (std::size_t s = 0; s < model.states().size(); ++s) {
    scale(static_cast<Eigen::Index>(s)) = spread_of(r, model.states()[s].name);
  }
  const auto size = [&](const VectorXd& d) {
    double out = 0;
    for (Eigen::Index i = 0; i < d.size(); ++i) {
      if (scale(i) > 0) out = std::max(out, std::abs(d(i)) / scale(i));
    }
    return out;
  };
  // Of a complex eigenvector, the real or imaginary part, whichever moves the measured states more.
  const VectorXd re = eigen.eigenvectors().col(growing).real();
  const VectorXd im = eigen.eigenvectors().col(growing).imag();
  const VectorXd direction = size(re) >= size(im) ? re : im;
  if (!(size(direction) > 0)) return std::nullopt;
  Runaway out;
  out.growth_rate = sigma;
  out.frequency_hz = std::abs(lambda(growing).imag()) / (2 * std::numbers::pi);
  // Dormand-Prince steps (Boost.Odeint, error controlled) for 4 ln(bound / start) e-folding
  // times: the linear growth reaches the bound in a quarter of them, a limit cycle or another
  // equilibrium in about as long. Held: the response's largest size in the last quarter is less
  // than twice that in the third. A response that grows faster than the linear one runs into the
  // bound, and one that a hardening spring slows (energy growing as exp(2 sigma t) under a y^4
  // potential is an amplitude growing as exp(sigma t / 2)) still grows 1000-fold in a quarter.
  namespace odeint = boost::numeric::odeint;
  using State = std::vector<double>;
  const auto rates = [&](const State& x, State& dxdt, double) {
    const VectorXd d = f(Eigen::Map<const VectorXd>(x.data(), f.states()));
    dxdt.assign(d.data(), d.data() + d.size());
  };
  auto stepper = odeint::make_controlled<odeint::runge_kutta_dopri5<State>>(1e-9, 1e-6);
  const double horizon = 4 * std::log(kRunawayBound / kRunawayStart) / sigma;
  const VectorXd start = *y0 + kRunawayStart / size(direction) * direction;
  State x(start.data(), start.data() + start.size());
  double t = 0, dt = 0.05 / std::abs(lambda(fastest)), third = 0, last = 0;
  for (long step = 0; step < kRunawaySteps && t < horizon; ++step) {
    const bool taken = stepper.try_step(rates, x, t, dt) == odeint::success;
    const double now = size(Eigen::Map<const VectorXd>(x.data(), f.states()) - *y0);
    // A step that shrinks to nothing: the response leaves in finite time.
    if (!std::isfinite(now) || now > kRunawayBound || !(dt > 1e-12 * horizon)) {
      out.time = t;
      return out;
    }
    if (!taken) continue;
    if (4 * t > 3 * horizon) {
      last = std::max(last, now);
    } else if (2 * t > horizon) {
      third = std::max(third, now);
    }
  }
  if (t < horizon || last > 2 * third) return out;
  return std::nullopt;  // held by its nonlinear terms
}

}  // namespace

std::optional<Runaway> runaway(const IdentifyResult& r) {
  if (!r.estimate.usable()) return std::nullopt;
  const auto finite = [](const std::vector<double>& values) {
    return std::all_of(values.begin(), values.end(), [](double x) { return std::isfinite(x); });
  };
  if (!finite(estimates_of(r)) || !finite(input_means(r))) return std::nullopt;
  const AlgebraLock lock;
  std::optional<Runaway> out;
  try {
    out = runaway_of(r);
  } catch (const Error&) {
    return std::nullopt;  // the estimates make no model to evaluate
  }
  if (out && out->frequency_hz > 0) {
    const LinearisedModes linear = linearised_modes(r);
    const auto mode = std::min_element(
        linear.modes.begin(), linear.modes.end(),
        [](const auto& a, const auto& b) { return a.damping_ratio < b.damping_ratio; });
    if (mode != linear.modes.end() && mode->damping_ratio < 0) {
      out->damping_ratio = mode->damping_ratio;
      out->damping_se = mode->damping_se;
    }
  }
  return out;
}

}  // namespace momentid
