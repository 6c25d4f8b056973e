// Text, LaTeX and JSON forms of a MomentSystem, and its equations as GiNaC expressions.

#include <algorithm>
#include <numeric>
#include <optional>
#include <sstream>

#include "common/json.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/derive.hpp"
#include "momentid/json.hpp"

namespace momentid {

DECLARE_FUNCTION_1P(expectation)
REGISTER_FUNCTION(expectation, set_name("E", "\\operatorname{E}"))
// rate(g): the record's rate of change of g, inside an expectation (rate_key).
DECLARE_FUNCTION_1P(rate)
REGISTER_FUNCTION(rate, set_name("rate"))

namespace {

using GiNaC::numeric;

std::string number_text(const numeric& q) {
  std::ostringstream out;
  out << q;
  return out.str();
}

bool is_one(const Monomial& m) {
  return std::all_of(m.begin(), m.end(), [](int e) { return e == 0; });
}

// How names look in one output format.
struct Notation {
  std::function<std::string(const Model&, const Monomial&)> moment;
  std::function<std::string(const std::string&)> name;
  std::function<std::string(const numeric&)> number;
  std::string times;
};

// "c*E[y^2]", "-2*E[y*v]", "3": one weighted term without its sign.
std::string weighted(const Notation& n, const numeric& weight, const std::string& what) {
  const numeric a = GiNaC::abs(weight);
  if (what.empty()) return n.number(a);
  if (a == 1) return what;
  return n.number(a) + n.times + what;
}

std::string combination(const Notation& n, const Model& model, const MomentCombination& c) {
  if (c.empty()) return "0";
  std::string out;
  for (const auto& [m, w] : c) {
    const std::string term = weighted(n, w, is_one(m) ? "" : n.moment(model, m));
    if (out.empty()) {
      out = (w.is_negative() ? "-" : "") + term;
    } else {
      out += (w.is_negative() ? " - " : " + ") + term;
    }
  }
  return out;
}

// sum over p of coefficient_p * p, grouped by parameter in declaration order.
std::string left_side(const Notation& n, const Model& model, const MomentEquation& eq) {
  std::string out;
  for (std::size_t p = 0; p < eq.coefficients.size(); ++p) {
    const MomentCombination& c = eq.coefficients[p];
    if (c.empty()) continue;
    const std::string name = n.name(model.parameters()[p].name);
    std::string term;
    bool negative = false;
    if (c.size() == 1) {
      const auto& [m, w] = *c.begin();
      negative = w.is_negative();
      term = weighted(n, w, is_one(m) ? name : name + n.times + n.moment(model, m));
    } else {
      term = name + n.times + "(" + combination(n, model, c) + ")";
    }
    if (out.empty()) {
      out = (negative ? "-" : "") + term;
    } else {
      out += (negative ? " - " : " + ") + term;
    }
  }
  return out;
}

std::string source_text(const Model& model, const MomentEquation& eq) {
  std::string out;
  for (const RowSource& s : eq.sources) {
    const numeric a = GiNaC::abs(s.factor);
    std::string one = a == 1 ? std::string() : number_text(a) + "*";
    one.append("[").append(model.equations()[s.equation].name()).append("]*");
    one.append(format_monomial(model, s.multiplier));
    if (out.empty()) {
      out = (s.factor.is_negative() ? "-" : "") + one;
    } else {
      out += (s.factor.is_negative() ? " - " : " + ") + one;
    }
  }
  return out;
}

const Notation& plain() {
  static const Notation n{
      [](const Model& model, const Monomial& m) { return format_moment(model, m); },
      [](const std::string& s) { return s; }, number_text, "*"};
  return n;
}

// Greek letter names and names ending in digits get their usual mathematical form.
std::string latex_name(const std::string& name) {
  static const std::map<std::string, std::string> greek{
      {"alpha", "\\alpha"}, {"beta", "\\beta"},      {"gamma", "\\gamma"},
      {"delta", "\\delta"}, {"eps", "\\varepsilon"}, {"epsilon", "\\varepsilon"},
      {"zeta", "\\zeta"},   {"eta", "\\eta"},        {"theta", "\\theta"},
      {"kappa", "\\kappa"}, {"lambda", "\\lambda"},  {"mu", "\\mu"},
      {"nu", "\\nu"},       {"xi", "\\xi"},          {"rho", "\\rho"},
      {"sigma", "\\sigma"}, {"tau", "\\tau"},        {"phi", "\\phi"},
      {"chi", "\\chi"},     {"psi", "\\psi"},        {"omega", "\\omega"},
      {"Omega", "\\Omega"}, {"Delta", "\\Delta"},    {"Gamma", "\\Gamma"}};
  std::size_t split = name.size();
  while (split > 0 && std::isdigit(static_cast<unsigned char>(name[split - 1]))) --split;
  if (split == 0) split = name.size();
  std::string base = name.substr(0, split);
  const std::string digits = name.substr(split);
  std::string escaped;
  for (char ch : base) escaped += ch == '_' ? std::string("\\_") : std::string(1, ch);
  if (auto it = greek.find(base); it != greek.end()) {
    base = it->second;
  } else if (base.size() > 1) {
    base = "\\mathit{" + escaped + "}";
  } else {
    base = escaped;
  }
  return digits.empty() ? base : base + "_{" + digits + "}";
}

std::string latex_number(const numeric& q) {
  if (q.is_integer()) return number_text(q);
  return "\\tfrac{" + number_text(q.numer()) + "}{" + number_text(q.denom()) + "}";
}

// variables()[v] in LaTeX: a state's or input's name, or |p| and sgn(p) for a function.
std::string latex_variable(const Model& model, std::size_t v) {
  if (model.variables()[v].channel()) return latex_name(model.variables()[v].name);
  const VariableFunction& f = model.function_of(model.variables()[v]);
  std::string p;
  for (const auto& [coefficient, monomial] : f.argument) {
    const numeric size = abs(coefficient);
    std::string term;
    for (std::size_t i = 0; i < monomial.size(); ++i) {
      if (monomial[i] == 0) continue;
      if (!term.empty()) term += "\\,";
      term += latex_name(model.variables()[i].name);
      if (monomial[i] > 1) term += "^{" + std::to_string(monomial[i]) + "}";
    }
    if (term.empty()) {
      term = latex_number(size);
    } else if (size != 1) {
      term = latex_number(size) + "\\," + term;
    }
    p += p.empty() ? (coefficient < 0 ? "-" : "") + term : (coefficient < 0 ? " - " : " + ") + term;
  }
  return f.kind == FunctionKind::kAbs ? "\\lvert " + p + "\\rvert"
                                      : "\\operatorname{sgn}(" + p + ")";
}

const Notation& latex() {
  static const Notation n{[](const Model& model, const Monomial& key) {
                            const Monomial m = key.without_rate();
                            std::string inside;
                            int factors = 0;
                            for (std::size_t i = 0; i < m.size(); ++i) {
                              if (m[i] == 0) continue;
                              if (!inside.empty()) inside += "\\,";
                              inside += latex_variable(model, i);
                              if (m[i] > 1) inside += "^{" + std::to_string(m[i]) + "}";
                              factors += m[i];
                            }
                            if (key.rate())
                              inside = factors > 1 ? "(" + inside + ")'" : inside + "'";
                            return "\\operatorname{E}[" + inside + "]";
                          },
                          latex_name, latex_number, "\\,"};
  return n;
}

// An equation's label, or its number (from 1) when it has none.
nlohmann::ordered_json json_equation_name(const Equation& eq) {
  return eq.label.empty() ? nlohmann::ordered_json(eq.number) : nlohmann::ordered_json(eq.label);
}

// Where a row came from: an equation times a multiplier, with the row's factor when it has one.
nlohmann::ordered_json json_source(const Model& model, int equation, const Monomial& multiplier) {
  return {{"equation", json_equation_name(model.equations()[equation])},
          {"multiplier", format_monomial(model, multiplier)}};
}

}  // namespace

std::string format_variable_latex(const Model& model, std::size_t v) {
  return latex_variable(model, v);
}

std::string format_moment(const Model& model, const Monomial& moment) {
  const AlgebraLock lock;
  if (moment.rate()) {
    const std::string inside = format_monomial(model, moment.without_rate());
    const bool single = moment.degree() == 1;
    return "E[" + (single ? inside : "(" + inside + ")") + "']";
  }
  return "E[" + format_monomial(model, moment) + "]";
}

std::string format_combination(const Model& model, const MomentCombination& c) {
  const AlgebraLock lock;
  return combination(plain(), model, c);
}

std::string format_text(const MomentSystem& system) {
  const AlgebraLock lock;
  const Model& model = *system.model;
  std::ostringstream out;
  out << "moment equations of " << model.name();
  if (!model.title().empty()) out << " (" << model.title() << ")";
  out << "\n\n";
  std::vector<std::string> sources;
  std::size_t width = 0;
  for (const MomentEquation& eq : system.equations) {
    sources.push_back(source_text(model, eq));
    width = std::max(width, sources.back().size());
  }
  const std::size_t number_width = std::to_string(system.equations.size()).size();
  for (std::size_t i = 0; i < system.equations.size(); ++i) {
    const MomentEquation& eq = system.equations[i];
    std::string number = std::to_string(i + 1);
    out << std::string(number_width - number.size() + 2, ' ') << number << "  " << sources[i]
        << std::string(width - sources[i].size() + 3, ' ') << left_side(plain(), model, eq) << " = "
        << combination(plain(), model, eq.rhs) << "\n";
  }
  if (system.equations.empty()) out << "  (none)\n";
  const std::size_t parameters = model.parameters().size();
  out << "\nequations: " << system.equations.size() << " (independent: " << system.generic_rank
      << " of " << parameters << " parameters";
  if (system.symmetric_rank < system.generic_rank) {
    out << "; " << system.symmetric_rank << " if odd moments vanish, as for symmetric systems";
  }
  out << ")\n";
  out << "parameters:";
  for (std::size_t p = 0; p < parameters; ++p)
    out << (p ? ", " : " ") << model.parameters()[p].name;
  out << "\nmoments needed: " << system.moments.size();
  for (std::size_t i = 0; i < system.moments.size(); ++i) {
    out << (i ? ", " : ": ") << format_moment(model, system.moments[i]);
  }
  out << "\nidentities used: " << system.identities.size() << "\n";
  for (const DataIdentity& id : system.identities) {
    out << "  " << format_moment(model, id.moment) << " = " << format_combination(model, id.value)
        << "\n";
  }
  out << "multipliers skipped: " << system.skipped.size() << "\n";
  for (const SkippedMultiplier& s : system.skipped) {
    out << "  [" << model.equations()[s.equation].name() << "]*"
        << format_monomial(model, s.multiplier) << ": " << s.reason << "\n";
  }
  for (const std::string& note : system.notes) out << "note: " << note << "\n";
  if (system.generic_rank < static_cast<int>(parameters)) {
    out << "warning: these equations cannot determine all " << parameters
        << " parameters; add multipliers (--degree or --multipliers)\n";
  }
  return out.str();
}

std::string format_latex(const MomentSystem& system) {
  const AlgebraLock lock;
  const Model& model = *system.model;
  std::ostringstream out;
  out << "% moment equations of " << model.name() << "; needs \\usepackage{amsmath}\n";
  out << "\\begin{align}\n";
  for (std::size_t i = 0; i < system.equations.size(); ++i) {
    const MomentEquation& eq = system.equations[i];
    out << "  " << left_side(latex(), model, eq) << " &= " << combination(latex(), model, eq.rhs);
    out << (i + 1 < system.equations.size() ? " \\\\\n" : "\n");
  }
  out << "\\end{align}\n";
  return out.str();
}

nlohmann::ordered_json json_value(const MomentSystem& system) {
  const AlgebraLock lock;
  const Model& model = *system.model;
  nlohmann::ordered_json out = {{"model", model.name()}};
  nlohmann::ordered_json& parameters = out["parameters"] = nlohmann::ordered_json::array();
  for (const Declaration& p : model.parameters()) parameters.push_back(p.name);
  nlohmann::ordered_json& moments = out["moments"] = nlohmann::ordered_json::array();
  for (const Monomial& m : system.moments) moments.push_back(format_moment(model, m));
  nlohmann::ordered_json& equations = out["equations"] = nlohmann::ordered_json::array();
  for (const MomentEquation& eq : system.equations) {
    const RowSource& first = eq.sources.front();
    nlohmann::ordered_json row = json_source(model, first.equation, first.multiplier);
    nlohmann::ordered_json& coefficients = row["coefficients"] = nlohmann::ordered_json::object();
    for (std::size_t p = 0; p < eq.coefficients.size(); ++p) {
      coefficients[model.parameters()[p].name] = format_combination(model, eq.coefficients[p]);
    }
    row["rhs"] = format_combination(model, eq.rhs);
    nlohmann::ordered_json& sources = row["sources"] = nlohmann::ordered_json::array();
    for (const RowSource& s : eq.sources) {
      sources.push_back(json_source(model, s.equation, s.multiplier));
      sources.back()["factor"] = number_text(s.factor);
    }
    equations.push_back(std::move(row));
  }
  out["independent"] = system.generic_rank;
  out["independent_if_symmetric"] = system.symmetric_rank;
  nlohmann::ordered_json& identities = out["identities"] = nlohmann::ordered_json::array();
  for (const DataIdentity& id : system.identities) {
    identities.push_back(format_moment(model, id.moment) + " = " +
                         format_combination(model, id.value));
  }
  nlohmann::ordered_json& skipped = out["skipped"] = nlohmann::ordered_json::array();
  for (const SkippedMultiplier& s : system.skipped) {
    skipped.push_back(json_source(model, s.equation, s.multiplier));
    skipped.back()["reason"] = s.reason;
  }
  out["notes"] = system.notes;
  return out;
}

std::string format_json(const MomentSystem& system) { return json_text(json_value(system)); }

GiNaC::ex moment_as_ex(const Model& model, const Monomial& moment) {
  GiNaC::ex product = 1;
  for (std::size_t i = 0; i < moment.size(); ++i) {
    product *= GiNaC::pow(model.variable_symbol(i), moment[i]);
  }
  return moment.rate() ? expectation(rate(product)) : expectation_of(product);
}

GiNaC::ex expectation_of(const GiNaC::ex& monomial) {
  return monomial.is_equal(1) ? GiNaC::ex(1) : expectation(monomial);
}

GiNaC::ex equation_as_ex(const Model& model, const MomentEquation& equation) {
  auto as_ex = [&](const MomentCombination& c) {
    GiNaC::ex sum = 0;
    for (const auto& [m, w] : c) sum += w * moment_as_ex(model, m);
    return sum;
  };
  GiNaC::ex out = -as_ex(equation.rhs);
  for (std::size_t p = 0; p < equation.coefficients.size(); ++p) {
    out += model.parameter_symbol(static_cast<int>(p)) * as_ex(equation.coefficients[p]);
  }
  return out;
}

}  // namespace momentid
