// The functions abs and sign of the states and inputs (VariableFunction): how moments that hold
// them behave when every state and input changes sign, and the commands that do not take them.

#include <algorithm>
#include <optional>

#include "momentid/algebra_lock.hpp"
#include "momentid/model.hpp"

namespace momentid {
namespace {

// The parity of a polynomial's terms: all of odd degree, all even, or mixed.
Parity parity_of(const std::vector<std::pair<GiNaC::numeric, Monomial>>& polynomial) {
  std::optional<Parity> out;
  for (const auto& [coefficient, monomial] : polynomial) {
    int degree = 0;
    for (int e : monomial) degree += e;
    const Parity p = degree % 2 == 1 ? Parity::kOdd : Parity::kEven;
    if (out && *out != p) return Parity::kNone;
    out = p;
  }
  return out.value_or(Parity::kEven);
}

}  // namespace

Parity parity(const Model& model, const Monomial& monomial) {
  const AlgebraLock lock;
  bool odd = false;
  // A rate E[(g)'] has g's parity.
  for (std::size_t i = 0; i < monomial.size(); ++i) {
    if (monomial[i] == 0) continue;
    const bool odd_power = monomial[i] % 2 == 1;
    const Variable& variable = model.variables()[i];
    if (variable.kind != VariableKind::kFunction) {
      if (odd_power) odd = !odd;
      continue;
    }
    // |p| is even when p has a parity; sign(p)^n as p^n, but sign(p)^2 is 1 whatever p.
    const VariableFunction& f = model.function_of(variable);
    const Parity p = parity_of(f.argument);
    const bool squared_sign = f.kind == FunctionKind::kSign && !odd_power;
    if (p == Parity::kNone && !squared_sign) return Parity::kNone;
    if (p == Parity::kOdd && f.kind == FunctionKind::kSign && odd_power) odd = !odd;
  }
  return odd ? Parity::kOdd : Parity::kEven;
}

bool holds_function(const std::vector<Variable>& variables, const Monomial& monomial) {
  for (std::size_t v = 0; v < monomial.size(); ++v) {
    if (monomial[v] != 0 && !variables[v].channel()) return true;
  }
  return false;
}

}  // namespace momentid
