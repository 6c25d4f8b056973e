// The chosen model as a model file (grammar/README.md): the library's declarations and equations
// without the dropped terms, constants substituted, parameters valued at their estimates.

#include <sstream>

#include "common/number.hpp"
#include "momentid/model.hpp"
#include "momentid/select.hpp"

namespace momentid {
namespace {

std::string numeric_text(const GiNaC::numeric& q) {
  std::ostringstream out;
  out << q;
  return out.str();
}

// One term, its sign given apart: `2*k*y^3`, `v'`, `eps*abs(v)*v`.
std::string term_text(const Model& model, const Term& t, const GiNaC::numeric& magnitude) {
  std::string factors;
  const auto add = [&](const std::string& f) { factors += (factors.empty() ? "" : "*") + f; };
  if (t.parameter >= 0) add(model.parameters()[static_cast<std::size_t>(t.parameter)].name);
  if (t.monomial.degree() > 0) add(format_monomial(model, t.monomial));
  if (t.derivative >= 0) add(model.states()[static_cast<std::size_t>(t.derivative)].name + "'");
  if (factors.empty()) return numeric_text(magnitude);
  return magnitude == 1 ? factors : numeric_text(magnitude) + "*" + factors;
}

// `terms` with the signs they carry: `-c*v - k*y + x`, or 0.
std::string side_text(const Model& model, const std::vector<std::pair<Term, bool>>& terms) {
  std::string out;
  for (const auto& [t, negate] : terms) {
    const GiNaC::numeric c = negate ? -t.coefficient : t.coefficient;
    const bool minus = c.is_negative();
    const std::string body = term_text(model, t, minus ? GiNaC::numeric(-c) : c);
    out += out.empty() ? (minus ? "-" : "") + body : (minus ? " - " : " + ") + body;
  }
  return out.empty() ? "0" : out;
}

}  // namespace

std::string chosen_model_text(const SelectResult& result) {
  // The chosen model's estimates once it is identified; the library's before.
  return subset_model_text(result, result.ranking.front().kept,
                           result.chosen.model ? result.chosen : result.library);
}

std::string subset_model_text(const SelectResult& result, const std::vector<bool>& kept,
                              const IdentifyResult& estimated) {
  const Model& model = *result.library.model;
  const auto value_of = [&](const Declaration& d) {
    for (const ParameterEstimate& e : estimated.parameters()) {
      if (e.name == d.name) return number(e.estimate, "%.10g");
    }
    return std::string("0");
  };
  std::ostringstream out;
  out << "# The terms of " << model.file() << " that momentid select kept on "
      << result.library.data_name << ";\n# the parameters' values are their estimates.\n";
  out << "model " << model.name();
  if (!model.title().empty()) out << " \"" << model.title() << "\"";
  out << "\n";
  const auto names = [&](const std::vector<Declaration>& list, const char* keyword) {
    if (list.empty()) return;
    out << keyword;
    for (std::size_t i = 0; i < list.size(); ++i) out << (i ? ", " : " ") << list[i].name;
    out << "\n";
  };
  names(model.states(), "state");
  names(model.inputs(), "input");
  std::string params;
  for (std::size_t p = 0; p < model.parameters().size(); ++p) {
    if (!kept[p]) continue;
    const Declaration& d = model.parameters()[p];
    params += (params.empty() ? "param " : ", ") + d.name + " = " +
              (d.fixed ? numeric_text(*d.value) : value_of(d)) + (d.fixed ? " fixed" : "");
  }
  if (!params.empty()) out << params << "\n";
  for (const MeasuredDerivative& m : model.measured_derivatives()) {
    out << "measured " << m.name << " = " << m.written << "\n";
  }
  for (const Equation& eq : model.equations()) {
    std::vector<std::pair<Term, bool>> left, right;
    for (const Term& t : eq.terms) {
      if (t.parameter >= 0 && !kept[static_cast<std::size_t>(t.parameter)]) continue;
      if (t.derivative >= 0) {
        left.emplace_back(t, false);
      } else {
        right.emplace_back(t, true);
      }
    }
    if (left.empty()) std::swap(left, right);
    for (auto& entry : left) entry.second = false;
    out << (eq.label.empty() ? "" : eq.label + ": ") << side_text(model, left) << " = "
        << side_text(model, right) << "\n";
  }
  for (const MultiplierSet& set : model.multipliers()) {
    out << "multipliers " << (set.equation.empty() ? "" : set.equation + ": ");
    for (std::size_t i = 0; i < set.monomials.size(); ++i) {
      out << (i ? ", " : "") << format_monomial(model, set.monomials[i]);
    }
    out << "\n";
  }
  return out.str();
}

}  // namespace momentid
