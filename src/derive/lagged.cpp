// Lagged moment equations: each equation with parameters, at time t, times an instrument at
// t - s, in expectation. Terms become cross-moment functions C[ψ;F](s) of measured channels and
// their derivatives in s; states without a column are read through kinematic equations
// (LagDeriver, lag_deriver.cpp).

#include "momentid/lagged.hpp"

#include <algorithm>

#include "derive/lag_deriver.hpp"
#include "momentid/algebra_lock.hpp"

namespace momentid {
namespace {

using GiNaC::numeric;

void add_to(LagCombination& into, const LagFunction& f, const numeric& w) {
  auto [it, inserted] = into.emplace(f, w);
  if (!inserted) {
    it->second += w;
    if (it->second.is_zero()) into.erase(it);
  }
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
  // Every term the data cannot carry is named at once (a library may hold several); forming
  // states lifts the error when it lifts each term's.
  std::vector<ModelError> cannot;
  bool formable = true;
  for (const Term& t : eq.terms) {
    try {
      terms.push_back(deriver.lag_function(eq, t, instrument, columns));
    } catch (const FormStatesError& error) {
      cannot.push_back(error);
    } catch (const ModelError& error) {
      cannot.push_back(error);
      formable = false;
    }
  }
  if (!cannot.empty()) {
    SourceLocation where = cannot.front().location();
    std::string message = cannot.front().message();
    if (cannot.size() > 1) {
      where = eq.where;
      message = std::to_string(cannot.size()) + " terms of equation " + eq.name() +
                " cannot be read from the data's channels (leave them out, or record the " +
                "channels they need):";
      for (const ModelError& error : cannot) message += "\n  " + error.message();
    }
    if (formable) throw FormStatesError(where, message, deriver.integral_state_names());
    throw ModelError(where, message);
  }
  // A state read as the integral of a column (y'' = a) enters at a negative order: its
  // cross-moments are known up to a polynomial in s, which the equation's derivative in s of
  // the order that clears the integrals drops, leaving the measured channels alone.
  int lowest = 0;
  for (const auto& [f, w] : terms) lowest = std::min(lowest, f.order);
  for (std::size_t i = 0; i < terms.size(); ++i) {
    auto& [f, w] = terms[i];
    f.order -= lowest;
    if (f.order > kMaxEliminatedOrder && eq.terms[i].order > 0) {
      throw ModelError(eq.where, "term '" + term_text(model, eq.terms[i]) + "' of equation " +
                                     eq.name() + " needs the derivative of order " +
                                     std::to_string(f.order) + " in the lag, above " +
                                     std::to_string(kMaxEliminatedOrder) +
                                     ": the latent states' elimination raised the equation's "
                                     "order beyond what the lagged equations read (measure one "
                                     "of the latent states)");
    }
    if (f.order > kMaxLagOrder && eq.terms[i].order == 0) {
      const std::string integrals = deriver.integral_states();
      throw FormStatesError(
          eq.where,
          "term '" + term_text(model, eq.terms[i]) + "' of equation " + eq.name() +
              " needs the derivative of order " + std::to_string(f.order) + " in the lag, above " +
              std::to_string(kMaxLagOrder) +
              ", to clear the integrals of the states read from a derivative column, " + integrals +
              " (measure them, or form them from their columns: add " + integrals + " to " +
              UsageError::mention("integrate") + ")",
          deriver.integral_state_names());
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

bool has_parameter(const Equation& eq) {
  return std::any_of(eq.terms.begin(), eq.terms.end(),
                     [](const Term& t) { return t.parameter >= 0; });
}

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
  int highest = 0;
  for (const LaggedEquation& row : system.equations) {
    for (const LagCombination& c : row.coefficients) {
      for (const auto& [f, w] : c) highest = std::max(highest, f.order);
    }
    for (const auto& [f, w] : row.rhs) highest = std::max(highest, f.order);
  }
  system.test_functions = lag_test_functions(system.first_lag, system.last_lag, highest);

  system.needed = needed_variables(system);
  return system;
}

}  // namespace momentid
