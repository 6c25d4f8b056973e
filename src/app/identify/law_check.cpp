// The law check (law_check.hpp): quadratic drag and Coulomb friction, each tested against the
// other by adding it to the model.

#include "app/identify/law_check.hpp"

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "momentid/error.hpp"
#include "momentid/model.hpp"

namespace momentid {
namespace {

// A term to add: its library target and text.
struct Addition {
  std::string equation, term;
};

// The state v when `f` is abs(v) or sign(v) of one state that is the rate of another (y' = v: a
// velocity), or -1.
int single_rate(const Model& model, const VariableFunction& f) {
  if (f.argument.size() != 1 || f.argument[0].first != 1) return -1;
  const Monomial& m = f.argument[0].second;
  if (m.degree() != 1) return -1;
  const auto v = static_cast<int>(std::find(m.begin(), m.end(), 1) - m.begin());
  return model.integral_of(v) >= 0 ? v : -1;
}

// The library target of equation `eq`: its label, or v' for the one state whose derivative it
// holds; empty when neither names it.
std::string target_of(const Model& model, const Equation& eq) {
  if (!eq.label.empty()) return eq.label;
  int state = -1;
  for (const Term& t : eq.terms) {
    if (t.derivative < 0) continue;
    if (state >= 0 && state != t.derivative) return "";
    state = t.derivative;
  }
  return state < 0 ? "" : model.states()[static_cast<std::size_t>(state)].name + "'";
}

// The other law of each drag or friction term whose equation lacks it.
std::vector<Addition> additions(const Model& model) {
  std::vector<Addition> out;
  for (const Equation& eq : model.equations()) {
    const std::string target = target_of(model, eq);
    if (target.empty()) continue;
    // Per state: the laws the equation has, abs(v)*v (drag) and sign(v) (friction).
    std::vector<int> drag(model.states().size(), 0), friction(model.states().size(), 0);
    for (const Term& t : eq.terms) {
      if (t.parameter < 0 || t.derivative >= 0) continue;
      for (std::size_t u = model.states().size(); u < t.monomial.size(); ++u) {
        const Variable& variable = model.variables()[u];
        if (t.monomial[u] != 1 || variable.channel()) continue;
        const VariableFunction& f = model.function_of(variable);
        const int v = single_rate(model, f);
        if (v < 0) continue;
        Monomial rest = t.monomial;
        rest[u] = 0;
        const auto s = static_cast<std::size_t>(v);
        if (f.kind == FunctionKind::kAbs && rest.degree() == 1 && rest[s] == 1) drag[s] = 1;
        if (f.kind == FunctionKind::kSign && rest.degree() == 0) friction[s] = 1;
      }
    }
    for (std::size_t s = 0; s < drag.size(); ++s) {
      if (drag[s] == friction[s]) continue;
      const std::string& v = model.states()[s].name;
      out.push_back({target, drag[s] ? "sign(" + v + ")" : "abs(" + v + ")*" + v});
    }
  }
  return out;
}

}  // namespace

void check_laws(IdentifyResult& result, const IdentifyOptions& options,
                const std::function<IdentifyResult(const Model&)>& identify_model) {
  const Model& model = *result.model;
  if (!options.law_check || model.functions().empty() || options.instruments ||
      options.multipliers || !result.estimate.usable()) {
    return;
  }
  const std::vector<Addition> added = additions(model);
  if (added.empty()) return;
  std::string text = model.text() + "\n";
  for (const Addition& a : added) text += "library " + a.equation + ": " + a.term + "\n";
  std::optional<Model> extended;
  try {
    extended = parse_model(text, model.file());
  } catch (const ModelError&) {
    return;  // a parameter name the library would give is taken
  }
  IdentifyResult with;
  try {
    with = identify_model(*extended);
  } catch (const Interrupted&) {
    throw;
  } catch (const Error&) {
    return;  // the check cannot be made (the added term leaves too few equations, ...)
  }
  if (!with.estimate.usable()) return;
  const std::vector<ParameterEstimate>& estimates = with.parameters();
  // The library's parameters follow the model's own, in the order of the additions.
  const std::size_t first = model.parameters().size();
  if (estimates.size() != first + added.size()) return;
  for (std::size_t k = 0; k < added.size(); ++k) {
    const ParameterEstimate& e = estimates[first + k];
    if (!(e.std_error > 0)) continue;
    result.law_checks.push_back({added[k].equation, added[k].term, e.estimate / e.std_error});
  }
}

}  // namespace momentid
