// The trapezoidal rule's bias on the moments of data whose input is held over each sample:
// E_dt[g] = E[g] + dt^2/12 * E[g''] + O(dt^4) (derive.hpp, held_input_corrections).

#include <map>

#include "momentid/algebra_lock.hpp"
#include "momentid/derive.hpp"

namespace momentid {
namespace {

// The exponents of `term`, a product of numbers, parameters and variables, over `variables`.
Monomial exponents_of(const GiNaC::ex& term, const std::vector<GiNaC::symbol>& variables) {
  Monomial out(variables.size());
  for (std::size_t i = 0; i < variables.size(); ++i) out[i] = term.degree(variables[i]);
  return out;
}

}  // namespace

HeldInputCorrections held_input_corrections(const Model& model,
                                            const std::vector<Monomial>& moments) {
  const AlgebraLock lock;
  HeldInputCorrections out;
  if (!model.functions().empty()) {
    out.unavailable = "abs(...) and sign(...) have no second derivative at their switches";
    return out;
  }
  const std::size_t states = model.states().size();
  std::vector<GiNaC::symbol> variables;
  for (std::size_t v = 0; v < model.variables().size(); ++v) {
    variables.push_back(model.variable_symbol(v));
  }
  // The derivatives as functions of the states and the (held) input.
  GiNaC::lst equations, derivatives;
  for (const Equation& eq : model.equations()) equations.append(eq.lhs == eq.rhs);
  for (std::size_t i = 0; i < states; ++i) {
    derivatives.append(model.derivative_symbol(static_cast<int>(i)));
  }
  GiNaC::ex solution;
  try {
    solution = GiNaC::lsolve(equations, derivatives);
  } catch (const std::exception&) {
    solution = GiNaC::lst{};
  }
  if (solution.nops() != states) {
    out.unavailable = "the equations do not give the derivatives of the states explicitly";
    return out;
  }
  // Polynomials in the states and inputs, over a denominator in the parameters at most, so that
  // g'' is a combination of moments.
  std::vector<GiNaC::ex> rate(states);
  for (std::size_t i = 0; i < states; ++i) {
    rate[i] = solution.op(i).rhs().normal();
    for (const GiNaC::symbol& v : variables) {
      if (rate[i].denom().has(v)) {
        out.unavailable = "the derivatives of the states are not polynomials in the states";
        return out;
      }
    }
  }
  const auto time_derivative = [&](const GiNaC::ex& g) {
    GiNaC::ex sum = 0;
    for (std::size_t i = 0; i < states; ++i) sum += g.diff(variables[i]) * rate[i];
    return sum;
  };
  // The products the second derivatives expand to: as many as the terms of each first
  // derivative times those of the rates. Past kMaxHeldTerms the symbolic work takes long
  // (10^6 products: 14 s).
  const auto terms_of = [](const GiNaC::ex& e) -> double {
    return GiNaC::is_a<GiNaC::add>(e) ? static_cast<double>(e.nops()) : 1.0;
  };
  double rate_terms = 0;
  for (const GiNaC::ex& r : rate) rate_terms += terms_of(r.expand());
  double products = 0;
  for (const Monomial& moment : moments) {
    GiNaC::ex g = 1;
    for (std::size_t i = 0; i < variables.size(); ++i) g *= GiNaC::pow(variables[i], moment[i]);
    products += terms_of(time_derivative(g).expand()) * rate_terms;
  }
  if (products > kMaxHeldTerms) {
    out.unavailable =
        "the model's " + std::to_string(static_cast<long>(rate_terms)) +
        " terms would make the correction expand " + std::to_string(static_cast<long>(products)) +
        " products, more than " + std::to_string(static_cast<long>(kMaxHeldTerms)) +
        " (seconds to minutes of symbolic work): give fewer terms, or --input-hold sample "
        "if the inputs were sampled rather than held";
    return out;
  }
  for (const Monomial& moment : moments) {
    GiNaC::ex g = 1;
    for (std::size_t i = 0; i < variables.size(); ++i) g *= GiNaC::pow(variables[i], moment[i]);
    // The sum of g'(t_{n+1}-) - g'(t_n+) over the intervals telescopes, and E[g''] = 0, unless
    // g' jumps at the samples: when it holds an input (held, or in the derivatives).
    const GiNaC::ex rate_of_g = time_derivative(g);
    bool jumps = false;
    for (std::size_t i = states; i < variables.size(); ++i) {
      jumps = jumps || rate_of_g.has(variables[i]);
    }
    if (!jumps) continue;
    // Expanded, not brought to a common denominator: with many terms that took minutes.
    std::map<Monomial, GiNaC::exvector, MomentOrder> terms;
    const GiNaC::ex numerator = time_derivative(rate_of_g).expand();
    const auto add = [&](const GiNaC::ex& term) {
      const Monomial m = exponents_of(term, variables);
      GiNaC::ex weight = term;
      for (std::size_t i = 0; i < variables.size(); ++i) {
        if (m[i] != 0) weight *= GiNaC::pow(variables[i], -m[i]);
      }
      terms[m].push_back(weight);
    };
    if (GiNaC::is_a<GiNaC::add>(numerator)) {
      for (const GiNaC::ex& term : numerator) add(term);
    } else if (!numerator.is_zero()) {
      add(numerator);
    }
    HeldInputCorrection c{moment, {}};
    for (auto& [m, weights] : terms) {
      const GiNaC::ex w = GiNaC::ex(GiNaC::add(weights)).normal();
      if (!w.is_zero()) c.second_derivative.emplace_back(m, w);
    }
    if (!c.second_derivative.empty()) out.moments.push_back(std::move(c));
  }
  return out;
}

}  // namespace momentid
