#pragma once

#include <ginac/ginac.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "momentid/model.hpp"
#include "momentid/moment.hpp"

namespace momentid {

// A cross-moment function of the lag s, or one of its derivatives in s:
//   C[ψ;F](s) = E[ψ(t − s)·F(t)],   C'[ψ;F](s) = d/ds C[ψ;F](s),   C''[ψ;F](s), ...
// with ψ (the instrument) and F monomials over the model's variables. By stationarity
// E[ψ(t − s)·dF/dt(t)] = C'[ψ;F](s): a time derivative of measured channels becomes a derivative
// in s of a smooth function that the data give without differentiating any signal.
struct LagFunction {
  Monomial instrument;
  Monomial function;
  int order = 0;  // derivatives in s
  friend auto operator<=>(const LagFunction&, const LagFunction&) = default;
};
using LagCombination = std::map<LagFunction, GiNaC::numeric>;

// Equation `equation` (index into Model::equations()) at time t times the instrument at t − s,
// in expectation: sum over p of coefficients[p] * theta_p = rhs, for every lag s of the system.
struct LaggedEquation {
  int equation = 0;
  Monomial instrument;
  std::vector<LagCombination> coefficients;  // one per parameter
  LagCombination rhs;
};

// A test function of the lag, in samples: φ(s) = (1 − u²)^p with u = (s − centre)/half_width,
// on |u| < 1. Each equation is summed over lags with weight φ(s); a lag derivative, taken by a
// central stencil, moves onto φ by summation by parts, which is exact over whole lags:
//   Σ_s φ(s) Σ_j w_j C(s + j) = Σ_s C(s) Σ_j w_j φ(s − j),
// and the weights on C are smooth (about (−1)^k φ^(k)), so that noise in the estimates of C is
// averaged, not differenced.
struct LagTestFunction {
  double centre = 0;
  double half_width = 1;
  int power = 8;

  double operator()(double s) const;  // 0 outside the support
};

// How to form the lagged moment equations.
struct LagOptions {
  // The lags s, in samples, whose cross-moments the equations read: the test functions and the
  // stencils they carry stay within first_lag..last_lag. The first lag must be at least 1:
  // white sensor noise on a channel biases its autocorrelation at lag 0 only.
  int first_lag = 3;
  int last_lag = 300;
  // Instruments, monomials in the measured channels and the model's abs and sign factors of
  // them; nullopt: each measured state and its highest power in the equations (y and y^3 for
  // the Duffing oscillator), and when the model has abs or sign terms, its cube and each such
  // term the data have (abs(v)*v).
  std::optional<std::vector<Monomial>> instruments;
  // Per channel (states, then inputs) or per model variable: whether the data have it. Empty:
  // all. An abs or sign of channels counts as measured when they all are (the pass computes
  // it from them), whatever its own flag.
  std::vector<bool> measured;

  static constexpr int kMaxLag = 10000;
  // The narrowest window: the test functions must span enough lags to be resolved.
  static constexpr int kMinSpan = 40;
  // Throws UsageError naming what is wrong: lags out of order, too few, or starting at lag 0;
  // an instrument in a channel that is not measured.
  void validate(const Model& model) const;
};

// The lagged moment equations: the linear system of the dynamical moment technique with
// instruments at earlier times. States without a column are expressed through kinematic
// equations (v = y' when y' = v), so that a record of displacement and force suffices. An
// abs(p) or sign(p) factor is read as a channel that the pass computes from the measured
// channels of p, so p must be measured (c2*abs(v)*v needs v's column, kc*abs(y)*y only y's).
//
// Example:
//   Model model = parse_model_file("models/duffing.mom");
//   LaggedSystem system = derive_lagged(model, {.measured = {true, false, true}});
//   std::cout << format_text(system);  // c*C'[y;y](s) + k*C[y;y](s) + eps*C[y;y^3](s) = ...
struct LaggedSystem {
  detail::AlgebraSpanStart algebra_start;  // copies and destruction hold the AlgebraLock
  const Model* model = nullptr;            // the model derived from, which must outlive the system
  int first_lag = 0, last_lag = 0;
  std::vector<LagTestFunction> test_functions;  // each equation is taken with each of them
  std::vector<Monomial> instruments;
  std::vector<LaggedEquation> equations;
  std::vector<bool> measured;  // per variable, as in LagOptions, a function as its argument
  // Per variable: the equations read its column, or for a function, compute it (its argument's
  // channels are then read too).
  std::vector<bool> needed;
  std::vector<std::string> derivatives;  // how unmeasured states are read, e.g. "v = y'"
  detail::AlgebraSpanEnd algebra_end;
};

// Whether the data, having the variables flagged in `measured`, show every variable of `model`:
// each one measured or, for a state, a derivative of a measured one through kinematic equations.
bool derivable_from(const Model& model, const std::vector<bool>& measured);

// How data with the variables flagged in `measured` show each variable of `model` (states, then
// inputs): `scale` times the `order`-th time derivative of the measured variable `base` (the
// variable itself, order 0, when measured; v = y' when y' = v and y is measured); base -1 when
// they do not show it.
struct VariableReading {
  int base = -1;
  int order = 0;
  double scale = 1;
};
std::vector<VariableReading> variable_readings(const Model& model,
                                               const std::vector<bool>& measured);

// Derives the lagged equations. Throws ModelError at an equation with a term that needs a
// channel the data lack (v^2 when only y is measured is not a time derivative of y), or naming
// a state that has no column and that no kinematic equation defines, or one inside an abs or
// sign factor; UsageError for bad options.
LaggedSystem derive_lagged(const Model& model, const LagOptions& options);

// Central stencils for the order-k lag derivative: C^(k)(s) ~ sum_j w_j C(s + j) / dt^k over
// j = -reach..reach, exact for polynomials of degree 2 reach (Fornberg's weights). The reach is
// `reach` for orders up to 2 and (k - 1) / 2 more above, so that the error is O(dt^(2 reach))
// for every order. Reach 2 (error O(dt^4)) suits records with inputs held over each sample,
// whose states have kinks at the samples that a wider stencil would straddle; band-limited
// records take a wider one (kWideStencilReach: O(dt^12)), which keeps its accuracy at a few
// samples per period. A model's terms read orders up to kMaxLagOrder (a state read through a
// derivative column beyond it is formed instead, --integrate); an equation with latent states
// eliminated (Term::order, latent.hpp) up to kMaxEliminatedOrder, its test functions kept the
// wider stencils' reach inside the window.
inline constexpr int kMaxLagOrder = 3;
inline constexpr int kMaxEliminatedOrder = 6;
inline constexpr int kStencilReach = 2;
inline constexpr int kWideStencilReach = 6;
int stencil_reach(int order, int reach);
std::vector<double> stencil_weights(int order, int reach = kStencilReach);

// The test functions for the lags first..last (at least LagOptions::kMinSpan of them), kept
// the widest stencil's reach inside the window: twenty overlapping ones across it, where the
// damping shows, and six narrower ones over its first fifth, where the instantaneous stiffness
// shows, when that fifth is wide enough to resolve them (half supports of at least 10 lags).
// `highest`: the highest order of the lag derivatives the equations read.
std::vector<LagTestFunction> lag_test_functions(int first_lag, int last_lag,
                                                int highest = kMaxLagOrder);

// The lagged moments E[ψ(t − s)·F(t)] behind C[ψ;F](s), as accumulator keys over the
// model's variables.
Moment lagged_moment(const Monomial& instrument, const Monomial& function, int lag);

// Text (docs/cli/derive.md, "Lagged equations"), LaTeX and JSON forms.
std::string format_lag_function(const Model& model, const LagFunction& f);
std::string format_text(const LaggedSystem& system);
std::string format_latex(const LaggedSystem& system);
std::string format_json(const LaggedSystem& system);

}  // namespace momentid
