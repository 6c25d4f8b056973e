#include "model/checks.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <set>

namespace momentid {
namespace {

// The equations must be solvable for the derivatives: the matrix of their coefficients
// (polynomials in states, inputs and parameters) has full column rank for generic values.
// Evaluated at random points; a rank that is full at any point is full generically.
void check_derivatives_independent(const Model& model) {
  const std::size_t n = model.states().size();
  const std::size_t m = model.equations().size();
  std::mt19937_64 engine(7);
  std::uniform_real_distribution<double> draw(0.5, 1.5);
  for (int attempt = 0; attempt < 3; ++attempt) {
    std::vector<double> variable(model.variables().size()), parameter(model.parameters().size());
    for (double& x : variable) x = draw(engine);
    for (double& x : parameter) x = draw(engine);
    Eigen::MatrixXd a =
        Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(n));
    for (std::size_t e = 0; e < m; ++e) {
      for (const Term& t : model.equations()[e].terms) {
        if (t.derivative < 0) continue;
        double value = t.coefficient.to_double();
        if (t.parameter >= 0) value *= parameter[t.parameter];
        for (std::size_t i = 0; i < t.monomial.size(); ++i) {
          value *= std::pow(variable[i], t.monomial[i]);
        }
        a(static_cast<Eigen::Index>(e), t.derivative) += value;
      }
    }
    Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
    lu.setThreshold(1e-9);
    if (lu.rank() == static_cast<Eigen::Index>(n)) return;
  }
  std::string names;
  for (const Declaration& s : model.states()) names += (names.empty() ? "" : ", ") + s.name;
  throw ModelError(model.equations().front().where,
                   "the equations cannot be solved for the derivatives of the states (" + names +
                       "): their coefficients are linearly dependent");
}

// Every state needs an equation of its own that contains its derivative: a matching between
// states and equations (augmenting paths; models are small).
void check_derivatives_determined(const Model& model) {
  const std::vector<Declaration>& states = model.states();
  const std::vector<Equation>& equations = model.equations();
  const std::size_t n = states.size();
  std::vector<std::set<int>> contains(n);
  for (std::size_t e = 0; e < equations.size(); ++e) {
    for (const Term& t : equations[e].terms) {
      if (t.derivative >= 0) contains[t.derivative].insert(static_cast<int>(e));
    }
  }
  for (std::size_t s = 0; s < n; ++s) {
    if (contains[s].empty()) {
      throw ModelError(states[s].where, "no equation determines the derivative of state '" +
                                            states[s].name + "' (no equation contains " +
                                            states[s].name + "')");
    }
  }
  std::vector<int> owner(equations.size(), -1);
  std::function<bool(int, std::vector<bool>&)> augment = [&](int s, std::vector<bool>& seen) {
    for (int e : contains[s]) {
      if (seen[e]) continue;
      seen[e] = true;
      if (owner[e] < 0 || augment(owner[e], seen)) {
        owner[e] = s;
        return true;
      }
    }
    return false;
  };
  for (std::size_t s = 0; s < n; ++s) {
    std::vector<bool> seen(equations.size(), false);
    if (!augment(static_cast<int>(s), seen)) {
      throw ModelError(states[s].where,
                       "no equation is left to determine the derivative of state '" +
                           states[s].name +
                           "': the equations containing it are needed for other states");
    }
  }
  check_derivatives_independent(model);
}

// abs(...) and sign(...) belong in equations with a parameter: an equation without one is
// kinematic (y' = f(y, u)), whose right side the stationarity identities substitute, and they
// need polynomials there.
void check_functions_have_parameters(const Model& model) {
  std::vector<bool> appears(model.functions().size(), false);
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      for (std::size_t i = 0; i < t.monomial.size(); ++i) {
        const Variable& variable = model.variables()[i];
        if (!variable.channel() && t.monomial[i] != 0) appears[variable.index] = true;
      }
    }
  }
  // One that cancels (abs(v) - abs(v)) would still be a variable, and a data channel to compute.
  for (std::size_t k = 0; k < appears.size(); ++k) {
    if (!appears[k]) {
      throw ModelError(model.functions()[k].where, model.functions()[k].name +
                                                       " cancels out of every equation: write the "
                                                       "equations without it");
    }
  }
  for (const Equation& eq : model.equations()) {
    const bool has_parameter = std::any_of(eq.terms.begin(), eq.terms.end(),
                                           [](const Term& t) { return t.parameter >= 0; });
    if (has_parameter) continue;
    for (const Term& t : eq.terms) {
      for (std::size_t i = 0; i < t.monomial.size(); ++i) {
        if (t.monomial[i] == 0 || model.variables()[i].channel()) continue;
        throw ModelError(eq.where, "equation " + eq.name() + " holds " + model.variables()[i].name +
                                       " but no unknown parameter: abs(...) and sign(...) may "
                                       "only appear in equations with parameters");
      }
    }
  }
}

}  // namespace

void EquationLabels::add(const SyntaxNode& label, int line) {
  const std::string name(label.text);
  if (auto it = lines_.find(name); it != lines_.end()) {
    source_.fail(label,
                 "label '" + name + "' is already used on line " + std::to_string(it->second));
  }
  lines_[name] = line;
  in_order_.push_back(name);
}

void EquationLabels::check_known(const SyntaxNode& label) const {
  const std::string name(label.text);
  if (lines_.count(name) != 0) return;
  std::string known;
  for (const std::string& l : in_order_) known += (known.empty() ? "" : ", ") + l;
  source_.fail(label,
               "no equation is labelled '" + name + "' (" +
                   (known.empty() ? std::string("no equation has a label") : "labels: " + known) +
                   ")");
}

void check_model(const Model& model, const Source& source) {
  if (model.states().empty()) {
    throw ModelError(source.start(), "the model declares no states (expected a 'state' statement)");
  }
  if (model.equations().empty()) throw ModelError(source.start(), "the model has no equations");

  std::vector<bool> used(model.parameters().size(), false);
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      if (t.parameter >= 0) used[t.parameter] = true;
    }
  }
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (!used[i]) {
      throw ModelError(model.parameters()[i].where,
                       "parameter '" + model.parameters()[i].name + "' appears in no equation");
    }
  }
  check_derivatives_determined(model);
  check_functions_have_parameters(model);
}

}  // namespace momentid
