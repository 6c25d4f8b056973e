#pragma once

#include <ginac/ginac.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "momentid/model.hpp"

namespace momentid {

// The order in which moments are listed: by total degree, then y^2 before y*v before v^2.
struct MomentOrder {
  bool operator()(const Monomial& a, const Monomial& b) const;
};

// A linear combination of observable moments E[monomial] with exact rational weights, listed in
// MomentOrder. The monomial of all zeros is E[1] = 1, i.e. a constant.
using MomentCombination = std::map<Monomial, GiNaC::numeric, MomentOrder>;

// Where a moment equation comes from: equation `equation` (index into Model::equations())
// multiplied by `multiplier` (a monomial in the states), scaled by `factor`.
struct RowSource {
  int equation = 0;
  Monomial multiplier;
  GiNaC::numeric factor = 1;
};

// One linear equation in the parameters: sum over p of coefficients[p] * theta_p = rhs, every
// coefficient and the right-hand side a combination of moments that must be estimated from data.
// Usually one equation times one multiplier; several sources when derivative moments that are
// known only in sums had to be eliminated by adding equations.
struct MomentEquation {
  std::vector<RowSource> sources;
  std::vector<MomentCombination> coefficients;  // one per parameter
  MomentCombination rhs;
};

// A pure-data identity that stationarity implies, E[moment] = value (e.g. E[y1*y2] = 0 when
// y1' = y2). The moment equations use `value` in place of E[moment] (with DeriveOptions::rates,
// plus the record's rates, which `value` leaves out); the identify stage reports how far the
// data violate it.
struct DataIdentity {
  Monomial moment;
  MomentCombination value;
};

// A multiplier that gave no usable moment equation, and why.
struct SkippedMultiplier {
  int equation = 0;
  Monomial multiplier;
  std::string reason;
};

// How to choose multipliers. `multipliers` (all equations) wins over `degree` (all monomials in
// the states of total degree 1..degree), which wins over the model's own `multipliers`
// statements; with none of these, the degree is raised from 1 until the equations determine
// every parameter even for symmetric data, with equations to spare for the model's test (at
// most kMaxAutomaticDegree; see derive()).
//
// `rates`: keep the record's rates of change (Monomial::rate()) where the stationarity identities
// would put 0, so that the equations hold exactly over a finite record, not only on average.
struct DeriveOptions {
  std::optional<std::vector<Monomial>> multipliers;
  int degree = 0;
  bool rates = false;
};

// The rate of change of a monomial g in the states over the record, E[d/dt g]. Stationarity
// makes it 0, and the stationarity identities take it to be; over a record of length T it is
// exactly (g(T) - g(0)) / T, so that a record that ends far from where it began leaves an
// error of that size in every equation that used an identity. With DeriveOptions::rates the
// equations keep these rates as terms of their MomentCombinations, under the key g.as_rate()
// (Monomial::rate()). format_moment writes it E[(g)'].
inline constexpr int kMaxAutomaticDegree = 3;
// At most this many products of an equation and a multiplier; `--degree` beyond it is refused
// (UsageError) and the automatic choice stops below it.
inline constexpr long kMaxProducts = 20000;

// The moment equations of a model: the linear system A(mu) theta = b(mu) of the dynamical
// moment technique, with the identities it used and the multipliers it could not use.
//
// Example:
//   Model model = parse_model_file("models/duffing.mom");
//   MomentSystem system = derive(model, {.degree = 3});
//   std::cout << format_text(system);
struct MomentSystem {
  detail::AlgebraSpanStart algebra_start;  // copies and destruction hold the AlgebraLock
  const Model* model = nullptr;
  std::vector<MomentEquation> equations;
  std::vector<Monomial> moments;  // every moment the equations need, in MomentOrder
  std::vector<DataIdentity> identities;
  std::vector<SkippedMultiplier> skipped;
  std::vector<std::string> notes;  // e.g. an equation without parameters that was not used
  // Rank of the coefficient matrix for generic moment values: how many parameters the
  // equations can determine at best.
  int generic_rank = 0;
  // The same when moments of odd total degree vanish, as for a system symmetric under
  // y, u -> -y, -u with a symmetric input: equations that only hold odd moments then say 0 = 0.
  int symmetric_rank = 0;
  // The same with the right-hand sides as one more column: above the number of parameters, the
  // equations that survive symmetric data have some to spare, which test the model.
  int symmetric_rank_with_rhs = 0;
  detail::AlgebraSpanEnd algebra_end;
};

// Derives the moment equations. Throws UsageError when `degree` would build more than
// kMaxProducts products (never for an equation that merely cannot be reduced: that multiplier is
// skipped and reported).
MomentSystem derive(const Model& model, const DeriveOptions& options = {});

// The second time derivative of a moment with the input held: what corrects its trapezoidal
// average on data whose input is held over each sample.
//
// With the input held over [t_n, t_{n+1}), the states' derivatives jump at every sample, and
// so does the derivative of g(y(t), u_n) for a monomial g. The trapezoidal rule's end
// corrections, which telescope for a smooth g, then add up (Euler-Maclaurin, interval by
// interval):
//   E_dt[g] = E[g] + dt^2/12 * E[g''] + O(dt^4),
// where g'' is the second derivative of g along the model with the input held on each
// interval, averaged over the intervals as the accumulator averages moments (HeldRule::
// kTrapezoidal). Where g' holds no input it is continuous and E[g''] = 0: those moments are left
// out. Each HeldInputCorrection gives E[g''] for one g as a combination of moments whose weights
// are functions of the parameters: rational when a parameter multiplies a derivative
// (`m*v' = ...` with m unknown).
//
// Example, the Duffing model (y' = v, v' = -c*v - k*y - eps*y^3 + x):
//   HeldInputCorrections h = held_input_corrections(model, {{0, 2, 0}});  // E[v^2]
//   // h.moments[0].second_derivative: E[(v^2)''] = 2 E[x^2] - 6c E[v*x] + ... as
//   // {monomial, weight} pairs, the weights in model.parameter_symbol(p).
struct HeldInputCorrection {
  Monomial moment;
  std::vector<std::pair<Monomial, GiNaC::ex>> second_derivative;
};
struct HeldInputCorrections {
  detail::AlgebraSpanStart algebra_start;    // copies and destruction hold the AlgebraLock
  std::vector<HeldInputCorrection> moments;  // those of `moments` whose derivative jumps
  std::string unavailable;  // why there are none although some might be needed, or empty
  detail::AlgebraSpanEnd algebra_end;
};
// Among `moments`, those whose derivative jumps; none, with `unavailable` saying why, when the
// equations do not give the derivatives of the states as polynomials in the states and inputs,
// or when the second derivatives would expand more than kMaxHeldTerms products (a model of
// many terms: minutes of symbolic work).
inline constexpr double kMaxHeldTerms = 1e6;
HeldInputCorrections held_input_corrections(const Model& model,
                                            const std::vector<Monomial>& moments);

// All monomials in `states` variables of total degree 1..degree, lowest degree first.
std::vector<Monomial> monomials_up_to(int states, int degree);
// How many there are, C(states + degree, degree) - 1, as a double (it may be huge).
double count_monomials(int states, int degree);

// Output formats (docs/cli/derive.md, "momentid derive").
std::string format_moment(const Model& model, const Monomial& moment);
// variables()[v] in LaTeX: a state's or input's name, |p| or \operatorname{sgn}(p) for a function.
std::string format_variable_latex(const Model& model, std::size_t v);
std::string format_combination(const Model& model, const MomentCombination& combination);
std::string format_text(const MomentSystem& system);
std::string format_latex(const MomentSystem& system);
std::string format_json(const MomentSystem& system);

// An equation as a GiNaC expression sum_p theta_p*A_p - b, the moments written as E(monomial)
// with the model's symbols, so that equations compare by subtraction.
GiNaC::ex equation_as_ex(const Model& model, const MomentEquation& equation);
GiNaC::ex moment_as_ex(const Model& model, const Monomial& moment);
// E(monomial) for a product of the model's symbols, as in equation_as_ex; E(1) is 1.
GiNaC::ex expectation_of(const GiNaC::ex& monomial);

}  // namespace momentid
