// How a record shows each variable of a model (LagDeriver): measured, a time derivative of a
// measured channel through kinematic equations, or an integral of a derivative column; and each
// term of an equation as a cross-moment function of the lag with an instrument.

#include "derive/lag_deriver.hpp"

#include <algorithm>
#include <optional>

namespace momentid {
namespace {

using GiNaC::numeric;

// The first channel of a function's argument that `measured` (per channel) lacks, or -1.
int missing_argument(const VariableFunction& f, const std::vector<bool>& measured) {
  for (const auto& [coefficient, monomial] : f.argument) {
    for (std::size_t c = 0; c < monomial.size(); ++c) {
      if (monomial[c] != 0 && !measured[c]) return static_cast<int>(c);
    }
  }
  return -1;
}

}  // namespace

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

LagDeriver::LagDeriver(const Model& model, const std::vector<bool>& measured)
    : model_(model),
      measured_(measured_variables(model, measured)),
      variables_(static_cast<int>(model.variables().size())),
      states_(static_cast<int>(model.states().size())),
      observed_(model.variables().size()) {
  for (int v = 0; v < variables_; ++v) observe(v, 0);
  integrate();
}

bool LagDeriver::read_both_ways(const Equation& eq) const {
  return std::any_of(eq.terms.begin(), eq.terms.end(), [&](const Term& t) {
    if (t.derivative < 0) return false;
    const int column = model_.measured_derivative_of(t.derivative);
    return column >= 0 && measured_[static_cast<std::size_t>(column)] &&
           observed_[t.derivative].base >= 0 && observed_[t.derivative].order >= 0;
  });
}

std::pair<LagFunction, numeric> LagDeriver::lag_function(const Equation& eq, const Term& t,
                                                         const Monomial& instrument,
                                                         bool columns) const {
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
  if (derivatives.empty()) return {{instrument, measured, t.order}, scale};
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
    return {{instrument, function, order + t.order}, scale / (power + 1)};
  }
  reject_term(eq, t);
}

std::vector<std::string> LagDeriver::integral_state_names() const {
  const auto integral = [&](int s) { return observed_[static_cast<std::size_t>(s)].order < 0; };
  const auto states = static_cast<int>(model_.states().size());
  std::vector<std::string> out;
  for (int s = 0; s < states; ++s) {
    bool derivative = false;
    for (int r = 0; r < states; ++r) {
      const std::optional<Kinematic> k = model_.kinematic(r);
      derivative |= integral(r) && k && k->state == s;
    }
    if (integral(s) && !derivative)
      out.push_back(model_.states()[static_cast<std::size_t>(s)].name);
  }
  return out;
}

std::string LagDeriver::integral_states(const std::string& except) const {
  std::string out;
  for (const std::string& name : integral_state_names()) {
    if (name != except) out += (out.empty() ? "" : ",") + name;
  }
  return out;
}

void LagDeriver::reject_term(const Equation& eq, const Term& t) const {
  // A state the data show only through a derivative column enters linearly or not at all.
  for (int v = 0; v < variables_; ++v) {
    const bool integral = (t.monomial[v] > 0 && observed_[v].order < 0) ||
                          (t.derivative == v && observed_[v].order < -1);
    if (!integral) continue;
    const std::string& name = model_.variables()[v].name;
    const std::string& column = model_.variables()[observed_[v].base].name;
    // Formed alone, the state may leave the others' integrals beyond the lag derivatives.
    const std::string others = integral_states(name);
    throw FormStatesError(
        eq.where,
        "term '" + term_text(model_, t) + "' of equation " + eq.name() +
            " needs a column for state '" + name + "': the record shows it only through '" +
            column + "' (" + definition(v) + "), which gives the terms linear in " + name +
            " alone (give the record a column '" + name + "', or form " + name + " from '" +
            column + "'" + (others.empty() ? "" : ", and " + others + " from theirs,") + " with " +
            UsageError::mention("integrate") + " " + integral_states() + ")",
        integral_state_names());
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

std::string LagDeriver::definition(int v) const {
  const Observation& o = observed_[v];
  const std::string& name = model_.variables()[v].name;
  const std::string scale = o.scale != 1 ? number_text(o.scale) + "*" : "";
  if (o.order < 0) return name + primes(-o.order) + " = " + scale + model_.variables()[o.base].name;
  return name + " = " + scale + model_.variables()[o.base].name + primes(o.order);
}

std::string LagDeriver::channel_kind(std::size_t v) const {
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

const Observation& LagDeriver::observe(int v, int depth) {
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
    const int state = model_.measured_derivatives()[static_cast<std::size_t>(variable.index)].state;
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

void LagDeriver::integrate() {
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

Observation LagDeriver::derivative_of(int state) const {
  const Observation& s = observed_[state];
  return {s.base, s.order + 1, s.scale, ""};
}

std::optional<Observation> LagDeriver::integral_of(int v) const {
  const std::optional<Kinematic> k = model_.kinematic(v);
  if (!k || k->state == v) return std::nullopt;
  const Observation& r = observed_[k->state];
  if (r.base < 0) return std::nullopt;
  return Observation{r.base, r.order - 1, r.scale * k->ratio, ""};
}

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

}  // namespace momentid
