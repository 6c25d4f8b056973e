#include "simulate/switching.hpp"

#include <algorithm>
#include <cmath>

namespace momentid {
namespace {

// Bisections that locate a switch: to 2^-30 of the step, far below the step's own error.
constexpr int kBisections = 30;

double side_of(double p) { return p > 0 ? 1.0 : p < 0 ? -1.0 : 0.0; }

}  // namespace

SwitchingStep::SwitchingStep(const CompiledModel& f)
    : f_(f),
      step_(f),
      n_(static_cast<std::size_t>(f.states())),
      m_(static_cast<std::size_t>(f.inputs())),
      ua_(m_),
      ub_(m_),
      uc_(m_),
      trial_(n_),
      dydt_(n_),
      at_(m_),
      rate_(n_) {}

bool SwitchingStep::slides(std::size_t k, const double* y, const double* u) {
  // Both sides drive the argument back to 0: with sign = +1 it falls, with -1 it rises.
  double rate[2];
  for (int side = 0; side < 2; ++side) {
    f_.set_mode(k, side == 0 ? 1.0 : -1.0);
    if (!f_.derivative(y, u, dydt_.data())) return false;
    rate[side] = f_.argument_rate(k, y, u, dydt_.data());
  }
  return rate[0] < 0 && rate[1] > 0;
}

bool SwitchingStep::start(const double* y, const double* u) {
  f_.set_sliding({});
  for (std::size_t k = 0; k < f_.functions(); ++k) f_.set_mode(k, NAN);
  std::vector<std::size_t> sliding;
  for (std::size_t k = 0; k < f_.functions(); ++k) {
    const double side = side_of(f_.argument(k, y, u));
    if (side != 0 || !f_.is_sign(k)) {
      f_.set_mode(k, side != 0 ? side : 1.0);
      continue;
    }
    if (slides(k, y, u)) {
      sliding.push_back(k);
      continue;
    }
    // The side the motion leaves to, or 0 (sign(0)) while it stays.
    f_.set_mode(k, 1.0);
    if (!f_.derivative(y, u, dydt_.data())) return false;
    const double up = f_.argument_rate(k, y, u, dydt_.data());
    f_.set_mode(k, -1.0);
    if (!f_.derivative(y, u, dydt_.data())) return false;
    const double down = f_.argument_rate(k, y, u, dydt_.data());
    f_.set_mode(k, up > 0 ? 1.0 : down < 0 ? -1.0 : 0.0);
  }
  f_.set_sliding(std::move(sliding));
  return true;
}

void SwitchingStep::inputs_at(double fraction, std::vector<double>& out) const {
  // The quadratic through the inputs at the start, middle and end of the step (exact for held
  // inputs, which give the same values three times).
  const double a = (1 - fraction) * (1 - 2 * fraction), b = 4 * fraction * (1 - fraction),
               c = fraction * (2 * fraction - 1);
  for (std::size_t i = 0; i < m_; ++i) out[i] = a * u0_[i] + b * um_[i] + c * u1_[i];
}

bool SwitchingStep::part(const double* y, double from, double length, double* out) {
  inputs_at(from, ua_);
  inputs_at(from + length / 2, ub_);
  inputs_at(from + length, uc_);
  std::copy(y, y + n_, out);
  return step_(out, ua_.data(), ub_.data(), uc_.data(), length * h_);
}

double SwitchingStep::switched(const double* y, const double* out, double at) const {
  // `at`: the fraction of the step where `out` is; y is where the part began, with inputs ua_.
  std::vector<double>& u = at_;
  inputs_at(at, u);
  double g = 1;
  const std::vector<std::size_t>& sliding = f_.sliding();
  if (!sliding.empty()) {
    if (!f_.derivative(out, u.data(), rate_.data())) return NAN;
    for (std::size_t k : sliding) g = std::min(g, 1 - std::abs(f_.mode(k)));
  }
  for (std::size_t k = 0; k < f_.functions(); ++k) {
    if (std::find(sliding.begin(), sliding.end(), k) != sliding.end()) continue;
    const double mode = f_.mode(k), end = f_.argument(k, out, u.data());
    if (mode == 0) {
      if (end != 0) g = std::min(g, -1.0);
      continue;
    }
    // Below the start's own value when that is already a hair across (a switch just located).
    const double before = std::min(0.0, f_.argument(k, y, ua_.data()) * mode);
    if (end * mode < before) g = std::min(g, end * mode - before);
  }
  return g;
}

bool SwitchingStep::change_modes(double* y, const double* u) {
  std::vector<double> rate(n_);
  if (!f_.sliding().empty() && !f_.derivative(y, u, rate.data())) return false;  // sigma at y
  std::vector<std::size_t> sliding;
  for (std::size_t k : f_.sliding()) {
    const double sigma = f_.mode(k);
    if (std::abs(sigma) < 1) {
      sliding.push_back(k);
    } else {
      f_.set_mode(k, side_of(sigma));
    }
  }
  f_.set_sliding(sliding);
  for (std::size_t k = 0; k < f_.functions(); ++k) {
    if (std::find(sliding.begin(), sliding.end(), k) != sliding.end()) continue;
    const double mode = f_.mode(k), side = side_of(f_.argument(k, y, u));
    if (mode == 0) {
      f_.set_mode(k, side);
    } else if (side == -mode) {
      if (f_.is_sign(k) && slides(k, y, u)) {
        sliding.push_back(k);
        f_.set_sliding(sliding);
        f_.project(k, y, u);
      } else {
        f_.set_mode(k, -mode);
      }
    }
  }
  return f_.derivative(y, u, rate.data());
}

void SwitchingStep::follow_sides(const double* y, const double* u, bool all) {
  for (std::size_t k = 0; k < f_.functions(); ++k) {
    const auto& sliding = f_.sliding();
    if (std::find(sliding.begin(), sliding.end(), k) != sliding.end()) continue;
    if (!all && !f_.reads_inputs(k)) continue;
    const double side = side_of(f_.argument(k, y, u));
    if (side != 0) f_.set_mode(k, side);
  }
}

bool SwitchingStep::operator()(double* y, const double* u_start, const double* u_middle,
                               const double* u_end, double h) {
  if (f_.functions() == 0) return step_(y, u_start, u_middle, u_end, h);
  u0_ = u_start;
  um_ = u_middle;
  u1_ = u_end;
  h_ = h;
  // A held input jumps between steps, where no switch is located: its functions take the side
  // the new value puts them on.
  follow_sides(y, u_start, false);
  double at = 0;
  bool chattering = false;
  for (int switches = 0;; ++switches) {
    if (!part(y, at, 1 - at, trial_.data())) return false;
    const double g = switched(y, trial_.data(), 1);
    if (std::isnan(g)) return false;
    chattering = switches == kMaxSwitches;
    if (chattering || g >= 0) break;
    double before = 0, after = 1 - at;
    for (int i = 0; i < kBisections; ++i) {
      const double middle = (before + after) / 2;
      if (!part(y, at, middle, trial_.data())) return false;
      const double gm = switched(y, trial_.data(), at + middle);
      if (std::isnan(gm)) return false;
      (gm < 0 ? after : before) = middle;
    }
    if (!part(y, at, after, trial_.data())) return false;
    std::copy(trial_.begin(), trial_.end(), y);
    at += after;
    inputs_at(at, ua_);
    if (!change_modes(y, ua_.data())) return false;
  }
  std::copy(trial_.begin(), trial_.end(), y);
  inputs_at(1, ua_);
  if (chattering) {
    // Switches left unlocated: every function on the side where the step ends, a sliding one
    // released where its value has left [-1, 1].
    if (!change_modes(y, ua_.data())) return false;
    follow_sides(y, ua_.data(), true);
  }
  for (std::size_t k : f_.sliding()) f_.project(k, y, ua_.data());
  return true;
}

}  // namespace momentid
