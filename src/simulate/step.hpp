#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "common/decimal.hpp"
#include "momentid/simulate.hpp"

namespace momentid {

// `c=0.5, k=4, eps=1`: the parameter values for messages.
inline std::string parameter_list(const Model& model, const std::vector<GiNaC::numeric>& values) {
  std::string out;
  for (std::size_t p = 0; p < values.size(); ++p) {
    out += (p ? ", " : "") + model.parameters()[p].name + "=" +
           shortest_decimal(values[p].to_double());
  }
  return out;
}

// One step of the classical fourth-order Runge-Kutta method, for `simulate` and for the replay
// of a recorded input: the inputs are given at the start, the middle and the end of the step
// (the same array three times for inputs held over it).
class RungeKuttaStep {
 public:
  explicit RungeKuttaStep(const CompiledModel& f)
      : f_(f),
        n_(static_cast<std::size_t>(f.states())),
        k1_(n_),
        k2_(n_),
        k3_(n_),
        k4_(n_),
        trial_(n_) {}

  // Advances y from t to t + h. Returns false, leaving y as it was or partly updated, when the
  // derivatives cannot be solved for at one of the stages.
  bool operator()(double* y, const double* u_start, const double* u_middle, const double* u_end,
                  double h) {
    if (!f_.derivative(y, u_start, k1_.data())) return false;
    for (std::size_t j = 0; j < n_; ++j) trial_[j] = y[j] + 0.5 * h * k1_[j];
    if (!f_.derivative(trial_.data(), u_middle, k2_.data())) return false;
    for (std::size_t j = 0; j < n_; ++j) trial_[j] = y[j] + 0.5 * h * k2_[j];
    if (!f_.derivative(trial_.data(), u_middle, k3_.data())) return false;
    for (std::size_t j = 0; j < n_; ++j) trial_[j] = y[j] + h * k3_[j];
    if (!f_.derivative(trial_.data(), u_end, k4_.data())) return false;
    for (std::size_t j = 0; j < n_; ++j) {
      y[j] += h / 6 * (k1_[j] + 2 * k2_[j] + 2 * k3_[j] + k4_[j]);
    }
    return true;
  }

  // The first state that is not finite or exceeds kBlowUpBound in magnitude, or -1.
  int blown_up(const double* y) const {
    bool finite = true;
    for (std::size_t j = 0; j < n_; ++j) finite = finite && std::abs(y[j]) <= kBlowUpBound;
    if (finite) return -1;
    for (std::size_t j = 0; j < n_; ++j) {
      if (!(std::abs(y[j]) <= kBlowUpBound)) return static_cast<int>(j);
    }
    return -1;
  }

 private:
  const CompiledModel& f_;
  std::size_t n_;
  std::vector<double> k1_, k2_, k3_, k4_, trial_;
};

}  // namespace momentid
