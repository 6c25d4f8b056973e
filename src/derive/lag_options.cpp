// What the lagged equations are formed with where the options leave it open: the default
// instruments and the test functions across the window of lags; and the checks of LagOptions.

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>

#include "derive/lag_deriver.hpp"

namespace momentid {
namespace {

// Whether `m` keeps its sign when every state and input changes sign (the symmetry of an
// oscillator without even terms): abs(p) is even, sign(p) as odd as p; a function of an argument
// of mixed degrees, which breaks the symmetry anyway, counts as even.
bool even_monomial(const Model& model, const Monomial& m) {
  int odd = 0;
  for (std::size_t v = 0; v < m.size(); ++v) {
    if (m[v] == 0) continue;
    const Variable& variable = model.variables()[v];
    int parity = 1;
    if (variable.kind == VariableKind::kFunction) {
      const VariableFunction& f = model.functions()[static_cast<std::size_t>(variable.index)];
      std::set<int> degrees;
      for (const auto& [c, monomial] : f.argument) {
        degrees.insert(std::accumulate(monomial.begin(), monomial.end(), 0) % 2);
      }
      if (degrees.size() != 1) return true;
      parity = f.kind == FunctionKind::kAbs ? 0 : *degrees.begin();
    }
    odd += parity * m[v];
  }
  return odd % 2 == 0;
}

// The power of variable `v` in the function that term `t` of `eq` is read as, or in the term
// itself when the data cannot carry it (lagged_equation says so).
int read_power(const LagDeriver& deriver, const Equation& eq, const Term& t, std::size_t v) {
  try {
    return deriver.lag_function(eq, t, Monomial(t.monomial.size(), 0), true).first.function[v];
  } catch (const ModelError&) {
    return t.monomial[v];
  }
}

}  // namespace

// Each measured state, and its highest power in the functions the equations' terms are read as
// (y^2*v with v = y' unmeasured is the lag derivative of y^3 / 3: y^3, the instrument that
// correlates with it on a symmetric structure, where y^2 left the Van der Pol oscillator's
// damping 4.5 times less certain). With abs or sign terms
// also its cube: the states alone correlate with v and |v|*v (or sign(v)) alike, which leaves
// their parameters nearly collinear, and the cubes tell them apart (on the drag, friction and
// clearance oscillators of docs/measured-data.md the standard errors of c2, f and kc fell 3 to
// 15 times). With a parameter on a term of even degree (y^2, y*v) also its square: on a
// symmetric structure such a term is uncorrelated with odd instruments, and its parameter left
// unidentified. Each term with a parameter and an abs or sign factor, when the data have every
// variable of it (|v|*v for drag, sign(v) for Coulomb friction): a wrong non-smooth law leaves a
// residual that is a function of the state at the same time, which the powers of the state at
// earlier times see only through their correlation with its odd powers, and the law's own shape
// at earlier times sees directly (drag fitted to Coulomb friction records read `ok` on 8 of 12
// records without it, 4 of 12 with it). And each input whose term has a parameter
// (docs/measured-data.md, "Instruments").
std::vector<Monomial> default_instruments(const Model& model, const std::vector<bool>& measured,
                                          const LagDeriver& deriver) {
  std::vector<Monomial> out;
  const int cube = model.functions().empty() ? 1 : 3;
  bool even = false;
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) even |= t.parameter >= 0 && even_monomial(model, t.monomial);
  }
  const int square = even ? 2 : 1;
  for (std::size_t v = 0; v < model.states().size(); ++v) {
    if (!measured[v]) continue;
    int highest = 1;
    for (const Equation& eq : model.equations()) {
      if (!has_parameter(eq)) continue;
      for (const Term& t : eq.terms) highest = std::max(highest, read_power(deriver, eq, t, v));
    }
    for (int power : {1, square, cube, highest}) {
      Monomial m(model.variables().size(), 0);
      m[v] = power;
      if (std::find(out.begin(), out.end(), m) == out.end()) out.push_back(m);
    }
  }
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      if (t.parameter < 0 || !holds_function(model.variables(), t.monomial)) continue;
      bool have = true;
      for (std::size_t v = 0; v < t.monomial.size(); ++v) have &= t.monomial[v] == 0 || measured[v];
      if (have && std::find(out.begin(), out.end(), t.monomial) == out.end()) {
        out.push_back(t.monomial);
      }
    }
  }
  // An input whose term has a parameter: the states at earlier times hardly correlate with a
  // broadband input, the input itself does.
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    const std::size_t v = model.states().size() + i;
    bool estimated = false;
    for (const Equation& eq : model.equations()) {
      for (const Term& t : eq.terms) estimated |= t.parameter >= 0 && t.monomial[v] > 0;
    }
    if (!measured[v] || !estimated) continue;
    Monomial m(model.variables().size(), 0);
    m[v] = 1;
    out.push_back(m);
  }
  // A derivative column stands for its state when the data show the state only through it.
  for (const MeasuredDerivative& d : model.measured_derivatives()) {
    const auto v = static_cast<std::size_t>(model.variable_index(d.name));
    if (!measured[v] || deriver.observation(d.state).order >= 0) continue;
    Monomial m(model.variables().size(), 0);
    m[v] = 1;
    out.push_back(m);
  }
  return out;
}

void LagOptions::validate(const Model& model) const {
  if (first_lag < 1) {
    throw UsageError(
        "lags: the first lag must be at least 1 (white sensor noise biases lag 0), "
        "found " +
        std::to_string(first_lag));
  }
  if (last_lag < first_lag + kMinSpan - 1 || last_lag > kMaxLag) {
    throw UsageError("lags: expected a last lag from " + std::to_string(first_lag + kMinSpan - 1) +
                     " to " + std::to_string(kMaxLag) + " (at least " + std::to_string(kMinSpan) +
                     " lags, for the test functions to resolve), found " +
                     std::to_string(last_lag));
  }
  if (!instruments || measured.empty()) return;
  const std::vector<bool> have = measured_variables(model, measured);
  for (const Monomial& m : *instruments) {
    for (std::size_t v = 0; v < m.size(); ++v) {
      if (m[v] != 0 && (v >= have.size() || !have[v])) {
        throw UsageError("instruments: " + format_monomial(model, m) + " uses " +
                         model.variables()[v].name + ", which the data do not have");
      }
    }
  }
}

double LagTestFunction::operator()(double s) const {
  const double u = (s - centre) / half_width;
  return std::abs(u) < 1 ? std::pow(1 - u * u, power) : 0.0;
}

std::vector<LagTestFunction> lag_test_functions(int first_lag, int last_lag, int highest) {
  // Evenly spread functions whose supports, each 4/(count + 1) of the window, overlap.
  std::vector<LagTestFunction> out;
  const auto spread = [&](double low, double high, int count, int power) {
    const double half_width = 2 * (high - low) / (count + 1);
    for (int i = 0; i < count; ++i) {
      const double centre =
          count == 1 ? (low + high) / 2
                     : low + half_width + i * (high - low - 2 * half_width) / (count - 1);
      out.push_back({centre, half_width, power});
    }
  };
  // The supports end where the functions vanish, the widest stencil's reach inside the lags.
  const int inset = stencil_reach(std::max(highest, kMaxLagOrder), kWideStencilReach);
  const double low = first_lag - 1 + inset;
  const double high = last_lag + 1 - inset;
  constexpr double kMinHalfWidth = 10;  // samples: finer ones the sums over lags do not resolve
  const int wide = std::clamp(static_cast<int>(2 * (high - low) / kMinHalfWidth) - 1, 1, 20);
  spread(low, high, wide, 10);
  const double first_fifth = (high - low) / 5;
  if (2 * first_fifth / 7 >= kMinHalfWidth) spread(low, low + first_fifth, 6, 8);
  return out;
}

}  // namespace momentid
