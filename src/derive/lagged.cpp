// Lagged moment equations: each equation with parameters, at time t, times an instrument at
// t - s, in expectation. Terms become cross-moment functions C[ψ;F](s) of measured channels and
// their derivatives in s; states without a column are read through kinematic equations.

#include "momentid/lagged.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/json.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/derive.hpp"
#include "momentid/json.hpp"

namespace momentid {
namespace {

using GiNaC::numeric;

// How the data show a model variable: `scale` times the `order`-th time derivative of the
// measured variable `base`.
struct Observation {
  int base = -1;  // -1: the data cannot show it
  int order = 0;
  numeric scale = 1;
  std::string reason;  // why not, when base is -1
};

std::string number_text(const numeric& q) {
  std::ostringstream out;
  out << q;
  return out.str();
}

std::string primes(int order) {
  return order <= 3 ? std::string(static_cast<std::size_t>(order), '\'')
                    : "^(" + std::to_string(order) + ")";
}

// A term as written in a model: 2*c*y^3, x, v', ...
std::string term_text(const Model& model, const Term& t) {
  std::string out;
  const numeric a = GiNaC::abs(t.coefficient);
  if (t.coefficient.is_negative()) out += "-";
  std::vector<std::string> factors;
  if (a != 1) factors.push_back(number_text(a));
  if (t.parameter >= 0) factors.push_back(model.parameters()[t.parameter].name);
  if (std::any_of(t.monomial.begin(), t.monomial.end(), [](int e) { return e != 0; })) {
    factors.push_back(format_monomial(model, t.monomial));
  }
  if (t.derivative >= 0) factors.push_back(model.states()[t.derivative].name + "'");
  if (factors.empty()) factors.push_back("1");
  for (std::size_t i = 0; i < factors.size(); ++i) out += (i ? "*" : "") + factors[i];
  return out;
}

// The first channel of a function's argument that `measured` (per channel) lacks, or -1.
int missing_argument(const VariableFunction& f, const std::vector<bool>& measured) {
  for (const auto& [coefficient, monomial] : f.argument) {
    for (std::size_t c = 0; c < monomial.size(); ++c) {
      if (monomial[c] != 0 && !measured[c]) return static_cast<int>(c);
    }
  }
  return -1;
}

// `flags` per channel (states, then inputs) or per variable, as per variable: a function is
// measured when its argument's channels are, for the pass computes it from them.
std::vector<bool> measured_variables(const Model& model, std::vector<bool> flags) {
  const std::size_t channels = model.channel_count();
  if (flags.size() != channels && flags.size() != model.variables().size()) {
    throw UsageError("lags: expected " + std::to_string(channels) +
                     " flags for the measured states and inputs (or " +
                     std::to_string(model.variables().size()) + " with the functions), found " +
                     std::to_string(flags.size()));
  }
  flags.resize(channels);
  for (const VariableFunction& f : model.functions()) {
    flags.push_back(missing_argument(f, flags) < 0);
  }
  return flags;
}

class LagDeriver {
 public:
  LagDeriver(const Model& model, const std::vector<bool>& measured)
      : model_(model),
        measured_(measured_variables(model, measured)),
        variables_(static_cast<int>(model.variables().size())),
        states_(static_cast<int>(model.states().size())),
        observed_(model.variables().size()) {
    for (int v = 0; v < variables_; ++v) observe(v, 0);
    integrate();
  }

  const Observation& observation(int v) const { return observed_[v]; }

  // Whether a term of `eq` reads a derivative from its column, and the same derivative is also
  // the derivative in s of its state's reading.
  bool read_both_ways(const Equation& eq) const {
    return std::any_of(eq.terms.begin(), eq.terms.end(), [&](const Term& t) {
      if (t.derivative < 0) return false;
      const int column = model_.measured_derivative_of(t.derivative);
      return column >= 0 && measured_[static_cast<std::size_t>(column)] &&
             observed_[t.derivative].base >= 0 && observed_[t.derivative].order >= 0;
    });
  }

  // The lag functions of one term, weighted, for instrument ψ: throws ModelError when the term
  // is not a time derivative of measured channels.
  // `columns`: read a derivative from the column that measures it, where there is one.
  std::pair<LagFunction, numeric> lag_function(const Equation& eq, const Term& t,
                                               const Monomial& instrument, bool columns) const {
    Monomial measured(variables_, 0);
    std::vector<std::pair<int, int>> derivatives;  // (base, order), one per factor
    const auto read = [&](int base, int order, int power) {
      if (order == 0) {
        measured[base] += power;
      } else {
        derivatives.insert(derivatives.end(), static_cast<std::size_t>(power), {base, order});
      }
    };
    numeric scale = t.coefficient;
    auto unobservable = [&](int v) {
      throw ModelError(eq.where, "term '" + term_text(model_, t) + "' of equation " + eq.name() +
                                     " needs " + observed_[v].reason);
    };
    // A function first: its message says which column the pass would compute it from.
    for (int v = 0; v < variables_; ++v) {
      if (!model_.variables()[v].channel() && t.monomial[v] != 0 && observed_[v].base < 0) {
        unobservable(v);
      }
    }
    for (int v = 0; v < variables_; ++v) {
      const int e = t.monomial[v];
      if (e == 0) continue;
      const Observation& o = observed_[v];
      if (o.base < 0) unobservable(v);
      scale *= GiNaC::pow(o.scale, numeric(e));
      read(o.base, o.order, e);
    }
    if (t.derivative >= 0) {
      // A column that holds the derivative is read as it is (C[ψ;a](s)), rather than as one
      // more derivative in s of the state's reading: no stencil differences its estimates.
      const int column = columns ? model_.measured_derivative_of(t.derivative) : -1;
      if (column >= 0 && measured_[static_cast<std::size_t>(column)]) {
        measured[column] += 1;
      } else {
        const Observation& o = observed_[t.derivative];
        if (o.base < 0) unobservable(t.derivative);
        scale *= o.scale;
        read(o.base, o.order + 1, 1);
      }
    }
    if (derivatives.empty()) return {{instrument, measured, 0}, scale};
    const auto [base, order] = derivatives.front();
    const int power = measured[base];
    measured[base] = 0;
    const bool rest_constant =
        std::all_of(measured.begin(), measured.end(), [](int e) { return e == 0; });
    if (derivatives.size() == 1 && rest_constant && (order == 1 || power == 0) &&
        order <= kMaxLagOrder) {
      // b^p * b' = d/dt b^(p+1) / (p+1); b^(k) alone is the k-th derivative of b, and a
      // negative k an integral, which derive_lagged differentiates away.
      Monomial function(variables_, 0);
      function[base] = power + 1;
      return {{instrument, function, order}, scale / (power + 1)};
    }
    // A state the data show only through a derivative column enters linearly or not at all.
    for (int v = 0; v < variables_; ++v) {
      const bool integral = (t.monomial[v] > 0 && observed_[v].order < 0) ||
                            (t.derivative == v && observed_[v].order < -1);
      if (!integral) continue;
      const std::string& name = model_.variables()[v].name;
      const std::string& column = model_.variables()[observed_[v].base].name;
      throw ModelError(eq.where, "term '" + term_text(model_, t) + "' of equation " + eq.name() +
                                     " needs a column for state '" + name +
                                     "': the record shows it only through '" + column + "' (" +
                                     definition(v) + "), which gives the terms linear in " + name +
                                     " alone (give the record a column '" + name + "', or form " +
                                     name + " from '" + column + "' with " +
                                     UsageError::mention("integrate") + " " + name + ")");
    }
    // Name the unmeasured variable the term would need, with how the data show it.
    std::string why = "channels the data lack: it is not a time derivative of measured channels";
    for (int v = 0; v < variables_; ++v) {
      if (t.monomial[v] > 0 && observed_[v].order > 0) {
        why = "a column for " + model_.variables()[v].name +
              ": it is not a time derivative of measured channels (" + definition(v) + ")";
        break;
      }
    }
    throw ModelError(
        eq.where, "term '" + term_text(model_, t) + "' of equation " + eq.name() + " needs " + why);
  }

  // "v = y'" for a state the data show as a derivative, "y'' = a" for one they show through
  // its derivative.
  std::string definition(int v) const {
    const Observation& o = observed_[v];
    const std::string& name = model_.variables()[v].name;
    const std::string scale = o.scale != 1 ? number_text(o.scale) + "*" : "";
    if (o.order < 0)
      return name + primes(-o.order) + " = " + scale + model_.variables()[o.base].name;
    return name + " = " + scale + model_.variables()[o.base].name + primes(o.order);
  }

 private:
  // "state " or "input ", for a message about a missing column.
  std::string channel_kind(std::size_t v) const {
    switch (model_.variables()[v].kind) {
      case VariableKind::kState:
        return "state ";
      case VariableKind::kInput:
        return "input ";
      case VariableKind::kDerivative:
      case VariableKind::kFunction:
        break;
    }
    return "measured column ";
  }

  // Fills observed_[v]; `depth` guards against kinematic cycles.
  const Observation& observe(int v, int depth) {
    Observation& o = observed_[v];
    if (o.base >= 0 || !o.reason.empty()) return o;
    const Variable& variable = model_.variables()[v];
    const std::string& name = variable.name;
    if (measured_[v]) {
      o.base = v;
      return o;
    }
    if (!variable.channel()) {
      const VariableFunction& f = model_.function_of(variable);
      const int c = missing_argument(f, measured_);
      o.reason = "a column for " + channel_kind(static_cast<std::size_t>(c)) +
                 model_.variables()[static_cast<std::size_t>(c)].name +
                 ": the lagged equations compute " + f.name +
                 " from the measured channels (give the record a column for " +
                 model_.variables()[static_cast<std::size_t>(c)].name + ")";
      return o;
    }
    o.reason = "a column for " + channel_kind(v) + name;
    if (variable.kind == VariableKind::kDerivative) {
      // Without its column, the derivative of how the data show its state.
      const int state =
          model_.measured_derivatives()[static_cast<std::size_t>(variable.index)].state;
      if (observe(state, depth + 1).base >= 0) o = derivative_of(state);
      return o;
    }
    if (variable.kind != VariableKind::kState || depth > states_) return o;
    // A kinematic equation a' = ratio*v shows v as a derivative of a.
    for (int a = 0; a < states_; ++a) {
      const std::optional<Kinematic> k = model_.kinematic(a);
      if (!k || k->state != v || a == v) continue;
      const Observation& r = observe(a, depth + 1);
      if (r.base < 0) continue;
      o.base = r.base;
      o.order = r.order + 1;
      o.scale = r.scale / k->ratio;
      o.reason.clear();
      return o;
    }
    o.reason += " (no kinematic equation such as y' = " + name + " defines it)";
    return o;
  }

  // Reads the states that observe() left unread through a column of their derivative (v' = a)
  // or a kinematic equation from a state so read (y' = v): as integrals of a measured channel,
  // negative orders. Only where no derivative reads them, so that the readings above stand.
  void integrate() {
    for (bool changed = true; changed;) {
      changed = false;
      for (int v = 0; v < states_; ++v) {
        Observation& o = observed_[v];
        if (o.base >= 0) continue;
        const int column = model_.measured_derivative_of(v);
        if (column >= 0 && measured_[static_cast<std::size_t>(column)]) {
          o = {column, -1, 1, ""};
        } else if (const std::optional<Observation> k = integral_of(v)) {
          o = *k;
        } else {
          continue;
        }
        changed = true;
      }
    }
    // An unmeasured derivative column whose state is now read.
    for (const MeasuredDerivative& d : model_.measured_derivatives()) {
      const int v = model_.variable_index(d.name);
      if (observed_[v].base < 0 && observed_[d.state].base >= 0)
        observed_[v] = derivative_of(d.state);
    }
  }

  // How the data show the derivative of `state`, which they show.
  Observation derivative_of(int state) const {
    const Observation& s = observed_[state];
    return {s.base, s.order + 1, s.scale, ""};
  }

  // A kinematic equation v' = ratio*w with w read: v as the integral of w's reading.
  std::optional<Observation> integral_of(int v) const {
    const std::optional<Kinematic> k = model_.kinematic(v);
    if (!k || k->state == v) return std::nullopt;
    const Observation& r = observed_[k->state];
    if (r.base < 0) return std::nullopt;
    return Observation{r.base, r.order - 1, r.scale * k->ratio, ""};
  }

  const Model& model_;
  std::vector<bool> measured_;
  int variables_, states_;
  std::vector<Observation> observed_;
};

void add_to(LagCombination& into, const LagFunction& f, const numeric& w) {
  auto [it, inserted] = into.emplace(f, w);
  if (!inserted) {
    it->second += w;
    if (it->second.is_zero()) into.erase(it);
  }
}

bool has_parameter(const Equation& eq) {
  return std::any_of(eq.terms.begin(), eq.terms.end(),
                     [](const Term& t) { return t.parameter >= 0; });
}

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

// Each measured state, and its highest power in the functions the equations' terms are read as
// (y^2*v with v = y' unmeasured is the lag derivative of y^3 / 3: y^3, the instrument that
// correlates with it on a symmetric structure, where y^2 left the Van der Pol oscillator's
// damping 4.5 times less certain). With abs or sign terms
// also its cube: the states alone correlate with v and |v|*v (or sign(v)) alike, which leaves
// their parameters nearly collinear, and the cubes tell them apart (on the drag, friction and
// clearance oscillators of docs/measured-data.md the standard errors of c2, f and kc fell 3 to
// 15 times). With a parameter on a term of even degree (y^2, y*v) also its square: on a
// symmetric structure such a term is uncorrelated with odd instruments, and its parameter left
// unidentified. And each input whose term has a parameter (docs/measured-data.md,
// "Instruments").
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

// Per variable, whether the equations read it; a function's argument's channels are read for it,
// as the pass computes it from them.
std::vector<bool> needed_variables(const LaggedSystem& system) {
  const Model& model = *system.model;
  std::vector<bool> needed(model.variables().size(), false);
  const auto mark = [&](const LagCombination& c) {
    for (const auto& [f, w] : c) {
      for (std::size_t v = 0; v < needed.size(); ++v) {
        if (f.instrument[v] != 0 || f.function[v] != 0) needed[v] = true;
      }
    }
  };
  for (const LaggedEquation& row : system.equations) {
    for (const LagCombination& c : row.coefficients) mark(c);
    mark(row.rhs);
  }
  for (std::size_t v = 0; v < model.variables().size(); ++v) {
    const Variable& variable = model.variables()[v];
    if (variable.channel() || !needed[v]) continue;
    const VariableFunction& f = model.function_of(variable);
    for (const auto& [coefficient, monomial] : f.argument) {
      for (std::size_t c = 0; c < monomial.size(); ++c) {
        if (monomial[c] != 0) needed[c] = true;
      }
    }
  }
  return needed;
}

}  // namespace

std::vector<VariableReading> variable_readings(const Model& model,
                                               const std::vector<bool>& measured) {
  const LagDeriver deriver(model, measured);
  std::vector<VariableReading> out;
  for (std::size_t v = 0; v < model.variables().size(); ++v) {
    const Observation& o = deriver.observation(static_cast<int>(v));
    out.push_back({o.base, o.order, o.scale.to_double()});
  }
  return out;
}

bool derivable_from(const Model& model, const std::vector<bool>& measured) {
  const LagDeriver deriver(model, measured);
  for (std::size_t v = 0; v < model.variables().size(); ++v) {
    if (deriver.observation(static_cast<int>(v)).base < 0) return false;
  }
  return true;
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
  if (!instruments) return;
  for (const Monomial& m : *instruments) {
    for (std::size_t v = 0; v < m.size(); ++v) {
      if (m[v] != 0 && !measured.empty() && (v >= measured.size() || !measured[v])) {
        throw UsageError("instruments: " + format_monomial(model, m) + " uses " +
                         model.variables()[v].name + ", which the data do not have");
      }
    }
  }
}

namespace {

// Equation e times `instrument` at t - s, in expectation (LagDeriver::lag_function for
// `columns`).
LaggedEquation lagged_equation(const Model& model, const LagDeriver& deriver, std::size_t e,
                               const Monomial& instrument, bool columns) {
  const Equation& eq = model.equations()[e];
  LaggedEquation row;
  row.equation = static_cast<int>(e);
  row.instrument = instrument;
  row.coefficients.resize(model.parameters().size());
  std::vector<std::pair<LagFunction, numeric>> terms;
  // Every term the data cannot carry is named at once (a library may hold several).
  std::vector<ModelError> cannot;
  for (const Term& t : eq.terms) {
    try {
      terms.push_back(deriver.lag_function(eq, t, instrument, columns));
    } catch (const ModelError& error) {
      cannot.push_back(error);
    }
  }
  if (cannot.size() == 1) throw cannot.front();
  if (!cannot.empty()) {
    std::string message = std::to_string(cannot.size()) + " terms of equation " + eq.name() +
                          " cannot be read from the data's channels (leave them out, or record " +
                          "the channels they need):";
    for (const ModelError& error : cannot) message += "\n  " + error.message();
    throw ModelError(eq.where, message);
  }
  // A state read as the integral of a column (y'' = a) enters at a negative order: its
  // cross-moments are known up to a polynomial in s, which the equation's derivative in s of
  // the order that clears the integrals drops, leaving the measured channels alone.
  int lowest = 0;
  for (const auto& [f, w] : terms) lowest = std::min(lowest, f.order);
  for (std::size_t i = 0; i < terms.size(); ++i) {
    auto& [f, w] = terms[i];
    f.order -= lowest;
    if (f.order > kMaxLagOrder) {
      throw ModelError(eq.where, "term '" + term_text(model, eq.terms[i]) + "' of equation " +
                                     eq.name() + " needs the derivative of order " +
                                     std::to_string(f.order) + " in the lag, above " +
                                     std::to_string(kMaxLagOrder) +
                                     ", to clear the integrals of the states read from a "
                                     "derivative column (measure one of them)");
    }
    const int parameter = eq.terms[i].parameter;
    if (parameter >= 0) {
      add_to(row.coefficients[static_cast<std::size_t>(parameter)], f, w);
    } else {
      add_to(row.rhs, f, -w);
    }
  }
  // The first parameter's first weight positive, as the zero-lag equations print.
  for (const LagCombination& c : row.coefficients) {
    if (c.empty()) continue;
    if (c.begin()->second.is_negative()) {
      for (auto& combination : row.coefficients) {
        for (auto& [f, w] : combination) w = -w;
      }
      for (auto& [f, w] : row.rhs) w = -w;
    }
    break;
  }
  return row;
}

}  // namespace

LaggedSystem derive_lagged(const Model& model, const LagOptions& options) {
  const AlgebraLock lock;
  const std::size_t variables = model.variables().size();
  const std::vector<bool> measured = measured_variables(
      model, options.measured.empty() ? std::vector<bool>(variables, true) : options.measured);
  const LagDeriver deriver(model, measured);
  const int states = static_cast<int>(model.states().size());

  LaggedSystem system;
  system.model = &model;
  system.first_lag = options.first_lag;
  system.last_lag = options.last_lag;
  system.measured = measured;
  for (int v = 0; v < states; ++v) {
    if (!measured[v] && deriver.observation(v).base >= 0) {
      system.derivatives.push_back(deriver.definition(v));
    }
  }
  system.instruments =
      options.instruments ? *options.instruments : default_instruments(model, measured, deriver);
  if (system.instruments.empty()) {
    throw UsageError("lags: no instruments: the data have none of the model's states");
  }
  for (std::size_t e = 0; e < model.equations().size(); ++e) {
    const Equation& eq = model.equations()[e];
    if (!has_parameter(eq)) continue;
    // A derivative that a column measures gives the equation twice: read from the column and as
    // a derivative in s of its state's cross-moments. The column's estimates carry its noise
    // undamped, the derivative's the differences of a smooth function: which is more precise
    // depends on the record, and the optimal weighting takes the best combination of the two.
    std::vector<bool> readings{true};
    if (deriver.read_both_ways(eq)) readings.push_back(false);
    for (const bool columns : readings) {
      for (const Monomial& instrument : system.instruments) {
        system.equations.push_back(lagged_equation(model, deriver, e, instrument, columns));
      }
    }
  }
  options.validate(model);
  system.test_functions = lag_test_functions(system.first_lag, system.last_lag);

  system.needed = needed_variables(system);
  return system;
}

double LagTestFunction::operator()(double s) const {
  const double u = (s - centre) / half_width;
  return std::abs(u) < 1 ? std::pow(1 - u * u, power) : 0.0;
}

std::vector<LagTestFunction> lag_test_functions(int first_lag, int last_lag) {
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
  const int inset = stencil_reach(kMaxLagOrder, kWideStencilReach);
  const double low = first_lag - 1 + inset;
  const double high = last_lag + 1 - inset;
  constexpr double kMinHalfWidth = 10;  // samples: finer ones the sums over lags do not resolve
  const int wide = std::clamp(static_cast<int>(2 * (high - low) / kMinHalfWidth) - 1, 1, 20);
  spread(low, high, wide, 10);
  const double first_fifth = (high - low) / 5;
  if (2 * first_fifth / 7 >= kMinHalfWidth) spread(low, low + first_fifth, 6, 8);
  return out;
}

int stencil_reach(int order, int reach) { return order == 3 ? reach + 1 : reach; }

std::vector<double> stencil_weights(int order, int reach) {
  if (order < 0 || order > kMaxLagOrder || reach < 1) {
    throw std::invalid_argument("stencil_weights: order " + std::to_string(order) + ", reach " +
                                std::to_string(reach) + ": expected an order from 0 to " +
                                std::to_string(kMaxLagOrder) + " and a reach from 1");
  }
  // Fornberg's recursion for the weights at the points -R..R of every derivative up to `order`
  // at 0 (B. Fornberg, Math. Comp. 51 (1988) 699-706).
  const int r = stencil_reach(order, reach);
  const int n = 2 * r + 1;
  std::vector<std::vector<double>> c(static_cast<std::size_t>(order + 1),
                                     std::vector<double>(static_cast<std::size_t>(n), 0.0));
  const auto x = [&](int i) { return static_cast<double>(i - r); };
  c[0][0] = 1;
  double c1 = 1;
  for (int i = 1; i < n; ++i) {
    const int top = std::min(i, order);
    double c2 = 1;
    for (int j = 0; j < i; ++j) {
      const double c3 = x(i) - x(j);
      c2 *= c3;
      const auto ui = static_cast<std::size_t>(i), uj = static_cast<std::size_t>(j);
      if (j == i - 1) {
        for (int k = top; k >= 1; --k) {
          const auto uk = static_cast<std::size_t>(k);
          c[uk][ui] = c1 * (k * c[uk - 1][ui - 1] - x(i - 1) * c[uk][ui - 1]) / c2;
        }
        c[0][ui] = -c1 * x(i - 1) * c[0][ui - 1] / c2;
      }
      for (int k = top; k >= 1; --k) {
        const auto uk = static_cast<std::size_t>(k);
        c[uk][uj] = (x(i) * c[uk][uj] - k * c[uk - 1][uj]) / c3;
      }
      c[0][uj] = x(i) * c[0][uj] / c3;
    }
    c1 = c2;
  }
  return c[static_cast<std::size_t>(order)];
}

Moment lagged_moment(const Monomial& instrument, const Monomial& function, int lag) {
  std::vector<MomentFactor> factors;
  for (std::size_t v = 0; v < instrument.size(); ++v) {
    if (instrument[v] != 0) factors.push_back({static_cast<int>(v), instrument[v], lag});
    if (function[v] != 0) factors.push_back({static_cast<int>(v), function[v], 0});
  }
  return Moment(std::move(factors));
}

std::string format_lag_function(const Model& model, const LagFunction& f) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, wrongly) about "C" + a temporary.
  std::string out = "C";
  out += primes(f.order);
  out.append("[").append(format_monomial(model, f.instrument));
  out.append(";").append(format_monomial(model, f.function)).append("](s)");
  return out;
}

namespace {

std::string combination_text(const Model& model, const LagCombination& c) {
  if (c.empty()) return "0";
  std::string out;
  for (const auto& [f, w] : c) {
    const numeric a = GiNaC::abs(w);
    const std::string term =
        (a == 1 ? std::string() : number_text(a) + "*") + format_lag_function(model, f);
    out += out.empty() ? (w.is_negative() ? "-" : "") + term
                       : (w.is_negative() ? " - " : " + ") + term;
  }
  return out;
}

std::string left_text(const Model& model, const LaggedEquation& eq) {
  std::string out;
  for (std::size_t p = 0; p < eq.coefficients.size(); ++p) {
    const LagCombination& c = eq.coefficients[p];
    if (c.empty()) continue;
    const std::string& name = model.parameters()[p].name;
    std::string term;
    bool negative = false;
    if (c.size() == 1) {
      const auto& [f, w] = *c.begin();
      negative = w.is_negative();
      const numeric a = GiNaC::abs(w);
      term = (a == 1 ? std::string() : number_text(a) + "*") + name + "*" +
             format_lag_function(model, f);
    } else {
      term = name + "*(" + combination_text(model, c) + ")";
    }
    out += out.empty() ? (negative ? "-" : "") + term : (negative ? " - " : " + ") + term;
  }
  return out;
}

// The channels (states and inputs) whose flag is set, or "none".
std::string channel_list(const Model& model, const std::vector<bool>& flags) {
  std::string out;
  for (std::size_t v = 0; v < model.channel_count(); ++v) {
    if (flags[v]) out += (out.empty() ? "" : ", ") + model.variables()[v].name;
  }
  return out.empty() ? "none" : out;
}

// The functions the equations read, which the pass computes from the channels.
std::vector<std::string> computed_functions(const LaggedSystem& system) {
  const Model& model = *system.model;
  std::vector<std::string> out;
  for (std::size_t v = 0; v < system.needed.size(); ++v) {
    if (!model.variables()[v].channel() && system.needed[v]) {
      out.push_back(model.variables()[v].name);
    }
  }
  return out;
}

// A monomial of a lag function in LaTeX: as format_monomial writes it, with |p| and sgn(p) for
// the functions.
std::string latex_monomial(const Model& model, const Monomial& m) {
  bool functions = false;
  for (std::size_t v = 0; v < m.size(); ++v)
    functions |= m[v] != 0 && !model.variables()[v].channel();
  if (!functions) return format_monomial(model, m);
  std::string out;
  for (std::size_t v = 0; v < m.size(); ++v) {
    if (m[v] == 0) continue;
    if (!out.empty()) out += "*";
    out += model.variables()[v].channel() ? model.variables()[v].name
                                          : format_variable_latex(model, v);
    if (m[v] > 1) out += "^{" + std::to_string(m[v]) + "}";
  }
  return out;
}

}  // namespace

std::string format_text(const LaggedSystem& system) {
  const AlgebraLock lock;
  const Model& model = *system.model;
  std::ostringstream out;
  out << "lagged moment equations of " << model.name();
  if (!model.title().empty()) out << " (" << model.title() << ")";
  out << ", lags s = " << system.first_lag << ".." << system.last_lag << " samples\n";
  out << "C[a;b](s) = E[a(t-s)*b(t)]; C'[a;b](s), C''[a;b](s): its derivatives in s\n\n";
  std::vector<std::string> sources;
  std::size_t width = 0;
  for (const LaggedEquation& eq : system.equations) {
    std::string source = "[";
    source += model.equations()[eq.equation].name();
    source += "] with " + format_monomial(model, eq.instrument) + "(t-s)";
    sources.push_back(std::move(source));
    width = std::max(width, sources.back().size());
  }
  const std::size_t number_width = std::to_string(system.equations.size()).size();
  for (std::size_t i = 0; i < system.equations.size(); ++i) {
    const std::string number = std::to_string(i + 1);
    out << std::string(number_width - number.size() + 2, ' ') << number << "  " << sources[i]
        << std::string(width - sources[i].size() + 3, ' ') << left_text(model, system.equations[i])
        << " = " << combination_text(model, system.equations[i].rhs) << "\n";
  }
  if (system.equations.empty()) out << "  (none)\n";
  const std::size_t tests = system.test_functions.size();
  out << "\nequations: " << system.equations.size() << " for every lag, taken with " << tests
      << " test functions phi(s) over lags " << system.first_lag << ".." << system.last_lag << ": "
      << system.equations.size() * tests << " in all\n";
  out << "channels read: " << channel_list(model, system.needed) << "\n";
  const std::vector<std::string> computed = computed_functions(system);
  for (std::size_t i = 0; i < computed.size(); ++i) {
    out << (i ? ", " : "computed from them: ") << computed[i]
        << (i + 1 < computed.size() ? "" : "\n");
  }
  for (const std::string& d : system.derivatives) out << "not measured: " << d << "\n";
  out << "lag derivatives: central differences in s (error O(dt^4), O(dt^12) for band-limited "
         "records), moved by parts onto phi(s) = (1-u^2)^p\n";
  return out.str();
}

std::string format_latex(const LaggedSystem& system) {
  const AlgebraLock lock;
  const Model& model = *system.model;
  auto lag = [&](const LagFunction& f) {
    return std::string("C") + (f.order == 0 ? "" : "^{(" + std::to_string(f.order) + ")}") + "_{" +
           format_monomial(model, f.instrument) + ",\\," + latex_monomial(model, f.function) +
           "}(s)";
  };
  auto combination = [&](const LagCombination& c) {
    std::string out;
    for (const auto& [f, w] : c) {
      const numeric a = GiNaC::abs(w);
      const std::string term = (a == 1 ? std::string() : number_text(a) + "\\,") + lag(f);
      out += out.empty() ? (w.is_negative() ? "-" : "") + term
                         : (w.is_negative() ? " - " : " + ") + term;
    }
    return out.empty() ? std::string("0") : out;
  };
  std::ostringstream out;
  out << "% lagged moment equations of " << model.name() << ", s = " << system.first_lag << ".."
      << system.last_lag << " samples; C_{a,b}(s) = E[a(t-s) b(t)]\n\\begin{align}\n";
  for (std::size_t i = 0; i < system.equations.size(); ++i) {
    const LaggedEquation& eq = system.equations[i];
    std::string left;
    for (std::size_t p = 0; p < eq.coefficients.size(); ++p) {
      if (eq.coefficients[p].empty()) continue;
      left += (left.empty() ? "" : " + ") + model.parameters()[p].name + "\\,(" +
              combination(eq.coefficients[p]) + ")";
    }
    out << "  " << left << " &= " << combination(eq.rhs)
        << (i + 1 < system.equations.size() ? " \\\\\n" : "\n");
  }
  out << "\\end{align}\n";
  return out.str();
}

nlohmann::ordered_json json_value(const LaggedSystem& system) {
  const AlgebraLock lock;
  const Model& model = *system.model;
  auto combination = [&](const LagCombination& c) {
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    for (const auto& [f, w] : c) {
      out.push_back({{"instrument", format_monomial(model, f.instrument)},
                     {"function", format_monomial(model, f.function)},
                     {"order", f.order},
                     {"weight", number_text(w)}});
    }
    return out;
  };
  nlohmann::ordered_json out = {{"model", model.name()},
                                {"lags", {system.first_lag, system.last_lag}}};
  nlohmann::ordered_json& parameters = out["parameters"] = nlohmann::ordered_json::array();
  for (const Declaration& p : model.parameters()) parameters.push_back(p.name);
  nlohmann::ordered_json& instruments = out["instruments"] = nlohmann::ordered_json::array();
  for (const Monomial& m : system.instruments) instruments.push_back(format_monomial(model, m));
  nlohmann::ordered_json& tests = out["test_functions"] = nlohmann::ordered_json::array();
  for (const LagTestFunction& f : system.test_functions) {
    tests.push_back({{"centre", f.centre}, {"half_width", f.half_width}, {"power", f.power}});
  }
  nlohmann::ordered_json& equations = out["equations"] = nlohmann::ordered_json::array();
  for (const LaggedEquation& eq : system.equations) {
    nlohmann::ordered_json coefficients = nlohmann::ordered_json::object();
    for (std::size_t p = 0; p < eq.coefficients.size(); ++p) {
      coefficients[model.parameters()[p].name] = combination(eq.coefficients[p]);
    }
    equations.push_back({{"equation", model.equations()[eq.equation].name()},
                         {"instrument", format_monomial(model, eq.instrument)},
                         {"coefficients", std::move(coefficients)},
                         {"rhs", combination(eq.rhs)}});
  }
  nlohmann::ordered_json& channels = out["channels"] = nlohmann::ordered_json::array();
  for (std::size_t v = 0; v < model.channel_count(); ++v) {
    if (system.needed[v]) channels.push_back(model.variables()[v].name);
  }
  if (!model.functions().empty()) out["computed"] = computed_functions(system);
  out["not_measured"] = system.derivatives;
  return out;
}

std::string format_json(const LaggedSystem& system) { return json_text(json_value(system)); }

}  // namespace momentid
