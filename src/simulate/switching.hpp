#pragma once

// Integration across the switches of abs(p) and sign(p): the right-hand side is smooth on either
// side of p = 0 but not across it, and a Runge-Kutta step over a switch loses its order (the
// error of that step is of the order of the step, not of its fifth power). The step is taken
// with each function in a mode (CompiledModel::set_mode) that continues its side smoothly; when
// an argument ends the step on the other side of 0, the switch is located (to a small fraction
// of the step), the step is taken up to it, the mode changes, and the rest of the step follows.
// A sign(p) whose two sides both drive p back to 0 holds p there (Filippov's sliding motion:
// Coulomb friction sticking) until the value it would need leaves [-1, 1].

#include <cstddef>
#include <vector>

#include "simulate/step.hpp"

namespace momentid {

class SwitchingStep {
 public:
  explicit SwitchingStep(const CompiledModel& f);

  // Sets the functions' modes for a motion that starts at y with inputs u (at rest, p = 0: a
  // sign that holds, or the side the motion leaves to). Returns false when the derivatives
  // cannot be solved for there.
  bool start(const double* y, const double* u);

  // Advances y from t to t + h as RungeKuttaStep does, locating the switches within the step.
  bool operator()(double* y, const double* u_start, const double* u_middle, const double* u_end,
                  double h);

  int blown_up(const double* y) const { return step_.blown_up(y); }

  // At most this many switches are located in one step; beyond (a chattering motion) the rest
  // of the step is taken as it comes, and the functions then take the sides where it ends.
  static constexpr int kMaxSwitches = 16;

 private:
  // The step from y over the fraction [from, from + length] of the step into `out`.
  bool part(const double* y, double from, double length, double* out);
  // The first function whose argument has switched in the part y -> out, as a value g that is
  // positive before a switch and negative after (the smallest over the functions).
  double switched(const double* y, const double* out, double at) const;
  // Changes the modes at a located switch, the state at y with inputs u.
  bool change_modes(double* y, const double* u);
  // Sets each function that is not sliding to the side of its argument at y, u where that is
  // not 0: those that read an input, or `all`.
  void follow_sides(const double* y, const double* u, bool all);
  // Whether sign function k, with those already sliding, would slide at y, u.
  bool slides(std::size_t k, const double* y, const double* u);
  void inputs_at(double fraction, std::vector<double>& out) const;

  const CompiledModel& f_;
  RungeKuttaStep step_;
  std::size_t n_, m_;
  const double *u0_ = nullptr, *um_ = nullptr, *u1_ = nullptr;
  double h_ = 0;
  std::vector<double> ua_, ub_, uc_, trial_, dydt_;
  // Scratch of switched(): the inputs where the part ends, the rates there.
  mutable std::vector<double> at_, rate_;
};

}  // namespace momentid
