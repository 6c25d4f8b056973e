// Text, LaTeX and JSON forms of a LaggedSystem, and the pieces of text that the messages of the
// lagged equations share.

#include <algorithm>
#include <sstream>

#include "common/json.hpp"
#include "derive/lag_deriver.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/derive.hpp"
#include "momentid/json.hpp"

namespace momentid {

using GiNaC::numeric;

std::string number_text(const numeric& q) {
  std::ostringstream out;
  out << q;
  return out.str();
}

std::string primes(int order) {
  return order <= 3 ? std::string(static_cast<std::size_t>(order), '\'')
                    : "^(" + std::to_string(order) + ")";
}

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
  if (t.order > 0) {
    // d^k/dt^k of the factors after the number and the parameter.
    const std::size_t first = (a != 1 ? 1 : 0) + (t.parameter >= 0 ? 1 : 0);
    std::string signal;
    for (std::size_t i = first; i < factors.size(); ++i)
      signal += (i > first ? "*" : "") + factors[i];
    const bool single = factors.size() == first + 1 && signal.find('^') == std::string::npos;
    factors.resize(first);
    factors.push_back((single ? signal : "(" + signal + ")") + primes(t.order));
  }
  if (factors.empty()) factors.push_back("1");
  for (std::size_t i = 0; i < factors.size(); ++i) out += (i ? "*" : "") + factors[i];
  return out;
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
