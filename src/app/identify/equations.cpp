// The identified model: the equations with the estimates substituted.

#include <algorithm>
#include <cmath>

#include "common/number.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {
namespace {

// A sum of coefficient * key, in the order the keys first appear.
template <typename Key>
using Sum = std::vector<std::pair<Key, double>>;

template <typename Key>
void add(Sum<Key>& into, const Key& key, double c) {
  const auto it =
      std::find_if(into.begin(), into.end(), [&](const auto& t) { return t.first == key; });
  if (it == into.end()) {
    into.emplace_back(key, c);
  } else {
    it->second += c;
  }
}

// `term` with a sign that joins it to the text before it: "-x" first, " - x" after.
std::string joined(const std::string& before, double c, const std::string& term) {
  return before + (before.empty() ? (c < 0 ? "-" : "") : (c < 0 ? " - " : " + ")) + term;
}

// Where a term goes: those in the states first (by degree, then in the order of the states),
// then those with an input, then the constant.
std::vector<int> term_order(const Model& model, const Monomial& m) {
  int degree = 0, input_degree = 0;
  for (std::size_t v = 0; v < m.size(); ++v) {
    degree += m[v];
    if (model.variables()[v].kind != VariableKind::kState) input_degree += m[v];
  }
  const int group = degree == 0 ? 2 : input_degree > 0 ? 1 : 0;
  std::vector<int> key{group, degree};
  for (int e : m) key.push_back(-e);
  return key;
}

// "-4*y - 0.5*v + x", terms of zero coefficient left out, "0" for none.
std::string sum_text(const Model& model, Sum<Monomial> sum) {
  std::stable_sort(sum.begin(), sum.end(), [&](const auto& a, const auto& b) {
    return term_order(model, a.first) < term_order(model, b.first);
  });
  std::string out;
  for (const auto& [m, c] : sum) {
    if (c == 0) continue;
    const std::string magnitude = number(std::abs(c), "%.6g");
    const std::string term = m.degree() == 0    ? magnitude
                             : magnitude == "1" ? format_monomial(model, m)
                                                : magnitude + "*" + format_monomial(model, m);
    out = joined(out, c, term);
  }
  return out.empty() ? std::string("0") : out;
}

// The derivative terms (state, factor) of an equation moved to the left: "2*y*v' + v'".
std::string derivatives_text(const Model& model, Sum<std::pair<int, Monomial>> derivatives) {
  std::stable_sort(derivatives.begin(), derivatives.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::string out;
  for (const auto& [key, c] : derivatives) {
    if (c == 0) continue;
    const std::string name = model.states()[static_cast<std::size_t>(key.first)].name + "'";
    const std::string factor =
        key.second.degree() == 0 ? name : format_monomial(model, key.second) + "*" + name;
    const std::string magnitude = number(std::abs(c), "%.6g");
    out = joined(out, c, magnitude == "1" ? factor : magnitude + "*" + factor);
  }
  return out.empty() ? std::string("0") : out;
}

// One equation with the estimates substituted: solved for its derivative when it has one with a
// number in front, otherwise with the derivative terms on the left.
std::string equation_text(const Model& model, const Equation& eq,
                          const std::vector<ParameterEstimate>& parameters) {
  // lhs - rhs = sum of derivative terms + sum of the others = 0.
  Sum<std::pair<int, Monomial>> derivatives;
  Sum<Monomial> rest;
  for (const Term& t : eq.terms) {
    double c = t.coefficient.to_double();
    if (t.parameter >= 0) c *= parameters[static_cast<std::size_t>(t.parameter)].estimate;
    if (t.derivative < 0) {
      add(rest, t.monomial, -c);
    } else {
      add(derivatives, std::make_pair(t.derivative, t.monomial), c);
    }
  }
  if (derivatives.size() == 1 && derivatives[0].first.second.degree() == 0 &&
      derivatives[0].second != 0) {
    for (auto& [m, c] : rest) c /= derivatives[0].second;
    return model.states()[static_cast<std::size_t>(derivatives[0].first.first)].name +
           "' = " + sum_text(model, rest);
  }
  return derivatives_text(model, derivatives) + " = " + sum_text(model, rest);
}

}  // namespace

std::vector<std::string> identified_equations(const IdentifyResult& r) {
  const AlgebraLock lock;
  if (!r.estimate.usable()) return {};
  std::vector<std::string> out;
  for (const Equation& eq : r.model->equations()) {
    out.push_back(equation_text(*r.model, eq, r.parameters()));
  }
  return out;
}

}  // namespace momentid
