#include "model/model_builder.hpp"

#include <algorithm>
#include <cctype>
#include <optional>
#include <sstream>

namespace momentid {
ModelBuilder::ModelBuilder(std::string_view text, std::string file)
    : source_(text, file), symbols_(source_), terms_(source_, symbols_), labels_(source_) {
  model_.file_ = std::move(file);
  model_.text_ = std::string(text);
}

Model ModelBuilder::build(const std::vector<SyntaxNode>& statements) {
  collect(statements);
  symbols_.make_symbols();
  model_.states_ = symbols_.states();
  model_.inputs_ = symbols_.inputs();
  model_.parameters_ = symbols_.parameters();
  model_.constants_ = symbols_.constants();
  model_.state_symbols_ = symbols_.state_symbols();
  model_.derivative_symbols_ = symbols_.derivative_symbols();
  model_.input_symbols_ = symbols_.input_symbols();
  model_.parameter_symbols_ = symbols_.parameter_symbols();
  for (const SyntaxNode* eq : equation_nodes_) add_equation(*eq);
  for (const SyntaxNode* library : library_nodes_) add_library(*library);
  for (const SyntaxNode* candidates : candidate_nodes_) add_candidates(*candidates);
  // The equations add the functions they use as variables: only now are they all known, and
  // every monomial gets their exponents.
  model_.functions_ = symbols_.functions();
  model_.function_symbols_ = symbols_.function_symbols();
  model_.variables_ = symbols_.variables();
  for (Equation& eq : model_.equations_) {
    for (Term& t : eq.terms) t.monomial.resize(model_.variables_.size());
  }
  model_.measured_symbols_ = symbols_.measured_symbols();
  for (std::size_t i = 0; i < symbols_.measured().size(); ++i) add_measured(i);
  for (const SyntaxNode* m : multiplier_nodes_) add_multipliers(*m);
  check_model(model_, source_);
  return std::move(model_);
}

// Refuses a name longer than kMaxName anywhere under `n`, without quoting it.
void ModelBuilder::check_name_lengths(const SyntaxNode& n) const {
  const bool name = n.kind == SyntaxKind::kModelName || n.kind == SyntaxKind::kDeclaredName ||
                    n.kind == SyntaxKind::kCandidateName || n.kind == SyntaxKind::kName ||
                    n.kind == SyntaxKind::kLabel;
  if (name && n.text.size() > kMaxName) {
    source_.fail(n, "a name of " + std::to_string(n.text.size()) +
                        " characters: a name has at most " + std::to_string(kMaxName));
  }
  for (const SyntaxNode& child : n.children) check_name_lengths(child);
}

void ModelBuilder::collect(const std::vector<SyntaxNode>& statements) {
  for (const SyntaxNode& n : statements) check_name_lengths(n);
  for (const SyntaxNode& n : statements) {
    if (n.kind == SyntaxKind::kModelStatement) {
      if (model_statement_ != nullptr) {
        source_.fail(n, "a second 'model' statement (the first is on line " +
                            std::to_string(model_statement_->line) + ")");
      }
      model_statement_ = &n;
      for (const SyntaxNode& part : n.children) {
        if (part.kind == SyntaxKind::kModelName) model_.name_ = part.text;
        if (part.kind == SyntaxKind::kStringBody) model_.title_ = part.text;
      }
    } else if (n.kind == SyntaxKind::kStateDeclaration) {
      symbols_.declare_all(n, SymbolKind::kState);
    } else if (n.kind == SyntaxKind::kInputDeclaration) {
      symbols_.declare_all(n, SymbolKind::kInput);
    } else if (n.kind == SyntaxKind::kParamDeclaration) {
      symbols_.declare_all(n, SymbolKind::kParameter);
    } else if (n.kind == SyntaxKind::kConstDeclaration) {
      symbols_.declare_all(n, SymbolKind::kConstant);
    } else if (n.kind == SyntaxKind::kMeasuredStatement) {
      symbols_.declare_measured(n);
    } else if (n.kind == SyntaxKind::kEquation) {
      equation_nodes_.push_back(&n);
      if (equation_nodes_.size() > kMaxEquations) {
        source_.fail(n, "one equation too many: a model has at most " +
                            std::to_string(kMaxEquations) + " equations");
      }
    } else if (n.kind == SyntaxKind::kMultipliersStatement) {
      multiplier_nodes_.push_back(&n);
    } else if (n.kind == SyntaxKind::kLibraryStatement) {
      library_nodes_.push_back(&n);
    } else if (n.kind == SyntaxKind::kCandidateStatement) {
      candidate_nodes_.push_back(&n);
    }
  }
  if (model_.name_.empty()) {
    std::string stem = model_.file_;
    if (auto slash = stem.find_last_of('/'); slash != std::string::npos) stem.erase(0, slash + 1);
    if (auto dot = stem.find('.'); dot != std::string::npos && dot > 0) stem.erase(dot);
    // A name from a file name keeps only characters that every output format can carry.
    for (char& ch : stem) {
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-') ch = '_';
    }
    model_.name_ = stem;
  }
}

void ModelBuilder::add_equation(const SyntaxNode& n) {
  // The label is checked before the sides are evaluated: it comes first in the text.
  std::string label;
  for (const SyntaxNode& c : n.children) {
    if (c.kind == SyntaxKind::kLabel) {
      labels_.add(c, static_cast<int>(n.line));
      label = c.text;
    }
  }
  Equation eq = terms_.equation(n);
  eq.label = std::move(label);
  eq.number = static_cast<int>(model_.equations_.size()) + 1;
  model_.equations_.push_back(std::move(eq));
}

void ModelBuilder::add_measured(std::size_t i) {
  const Declaration& column = symbols_.measured()[i];
  const SyntaxNode& target = *symbols_.measured_targets()[i];
  const SyntaxNode& name_node = target.children.at(0);
  const std::string name(name_node.text);
  const std::size_t order = target.children.at(1).text.size();
  symbols_.derivative(name_node, name);  // a declared state
  const auto state_of = [&](const std::string& s) {
    return static_cast<int>(std::find_if(model_.states_.begin(), model_.states_.end(),
                                         [&](const Declaration& d) { return d.name == s; }) -
                            model_.states_.begin());
  };
  int state = state_of(name);
  if (order > 2) {
    source_.fail(target.children.at(1),
                 "a measured column holds a state's first or second "
                 "derivative (v' or y''), found order " +
                     std::to_string(order));
  }
  const auto number = [](const GiNaC::numeric& q) {
    std::ostringstream out;
    out << q;
    return out.str();
  };
  if (order == 2) {
    const std::optional<Kinematic> k = model_.kinematic(state);
    if (!k || k->ratio != 1) {
      source_.fail(target, name + "'' needs an equation " + name +
                               "' = w with a state w, whose derivative the column then holds "
                               "(write 'measured " +
                               column.name + " = w'' with that state)");
    }
    state = k->state;
  }
  const std::string& holds = model_.states_[static_cast<std::size_t>(state)].name;
  if (const std::optional<Kinematic> k = model_.kinematic(state)) {
    const std::string& w = model_.states_[static_cast<std::size_t>(k->state)].name;
    source_.fail(target, holds + "' = " + (k->ratio == 1 ? "" : number(k->ratio) + "*") + w +
                             " (equation " + k->equation->name() + "): a column holding " + holds +
                             "' holds " + w + (k->ratio == 1 ? "" : " scaled") +
                             ", which a record gives as the state's own column (--columns \"" + w +
                             "=COLUMN\")");
  }
  for (const MeasuredDerivative& other : model_.measured_) {
    if (other.state == state) {
      source_.fail(target, "'" + other.name + "' (line " + std::to_string(other.where.line) +
                               ") already holds " + holds + "'");
    }
  }
  model_.measured_.push_back({column.name, state, std::string(target.text), column.where});
}

namespace {

// A parameter's name for a library term: the equation's name, then each factor's name (letters,
// digits and '_' of it) with its exponent, as in v_y2_x for y^2*x in the equation of v', or
// v_const for the constant 1.
std::string library_parameter_name(const std::string& prefix,
                                   const std::vector<Variable>& variables, const Monomial& m) {
  if (std::all_of(m.begin(), m.end(), [](int e) { return e == 0; })) return prefix + "_const";
  std::string out = prefix;
  for (std::size_t v = 0; v < m.size(); ++v) {
    if (m[v] == 0) continue;
    std::string factor;
    for (const char ch : variables[v].name) {
      if (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_') factor += ch;
    }
    if (m[v] > 1) {
      // y1^2 is y1p2, not y12.
      if (std::isdigit(static_cast<unsigned char>(factor.back()))) factor += 'p';
      factor += std::to_string(m[v]);
    }
    out += "_" + factor;
  }
  return out;
}

// `m` and `other` over the same variables: the shorter padded with zeros.
bool same_monomial(Monomial m, Monomial other) {
  const std::size_t size = std::max(m.size(), other.size());
  m.resize(size);
  other.resize(size);
  return m == other;
}

}  // namespace

Equation& ModelBuilder::library_equation(const SyntaxNode& target) {
  const SyntaxNode& name_node = target.children.at(0);
  const std::string name(name_node.text);
  auto& equations = model_.equations_;
  if (target.children.size() == 1) {
    const auto it = std::find_if(equations.begin(), equations.end(),
                                 [&](const Equation& eq) { return eq.label == name; });
    if (it == equations.end()) {
      const Declaration* d = symbols_.find(name);
      source_.fail(target, d && d->kind == SymbolKind::kState
                               ? "no equation is labelled '" + name + "': write " + name +
                                     "' for the equation of its derivative"
                               : "no equation is labelled '" + name +
                                     "': name the equation by a label or by a state's "
                                     "derivative, as in 'library v': ...'");
    }
    return *it;
  }
  if (target.children.at(1).text.size() != 1) {
    source_.fail(target, "expected a state's first derivative, as in v', found '" +
                             std::string(target.text) + "'");
  }
  symbols_.derivative(name_node, name);  // a declared state
  const auto state =
      static_cast<int>(std::find_if(model_.states_.begin(), model_.states_.end(),
                                    [&](const Declaration& d) { return d.name == name; }) -
                       model_.states_.begin());
  std::vector<Equation*> holding;
  for (Equation& eq : equations) {
    if (std::any_of(eq.terms.begin(), eq.terms.end(),
                    [&](const Term& t) { return t.derivative == state; })) {
      holding.push_back(&eq);
    }
  }
  if (holding.size() != 1) {
    std::string which;
    for (const Equation* eq : holding) which += (which.empty() ? "" : " and ") + eq->name();
    source_.fail(target, holding.empty() ? "no equation holds " + name + "'"
                                         : name + "' is in equations " + which +
                                               ": label the one the terms join and name it");
  }
  return *holding[0];
}

void ModelBuilder::add_library(const SyntaxNode& n) {
  const SyntaxNode* target = nullptr;
  for (const SyntaxNode& c : n.children) {
    if (c.kind == SyntaxKind::kLibraryTarget) target = &c;
  }
  Equation& eq = library_equation(*target);
  const std::string prefix(target->children.at(0).text);
  for (const SyntaxNode& item : n.children) {
    if (item.kind != SyntaxKind::kLibraryTerm) continue;
    for (const TermBuilder::LibraryTerm& t : terms_.library_terms(item)) {
      const std::vector<Variable>& variables = symbols_.variables();
      const auto present = std::find_if(eq.terms.begin(), eq.terms.end(), [&](const Term& other) {
        return other.parameter >= 0 && other.derivative < 0 &&
               same_monomial(other.monomial, t.monomial);
      });
      if (present != eq.terms.end()) {
        if (t.generated) continue;
        const Declaration& p = model_.parameters_[static_cast<std::size_t>(present->parameter)];
        source_.fail(item, "'" + std::string(item.text) + "' is already a term of equation " +
                               eq.name() + ", with parameter " + p.name +
                               (p.candidate ? "" : ": write 'candidate " + p.name + "' instead"));
      }
      const std::string name = library_parameter_name(prefix, variables, t.monomial);
      const auto made = std::find_if(model_.parameters_.begin(), model_.parameters_.end(),
                                     [&](const Declaration& d) { return d.name == name; });
      if (const Declaration* d = made != model_.parameters_.end() ? &*made : symbols_.find(name)) {
        source_.fail(item, "the library names the parameter of '" + std::string(item.text) + "' " +
                               name + ", which is declared as " + kind_with_article(d->kind) +
                               " on line " + std::to_string(d->where.line) +
                               ": rename that declaration");
      }
      const Declaration p{.name = name,
                          .kind = SymbolKind::kParameter,
                          .value = std::nullopt,
                          .where = source_.where(item),
                          .fixed = false,
                          .candidate = true};
      model_.parameters_.push_back(p);
      model_.parameter_symbols_.emplace_back(name);
      const GiNaC::symbol& symbol = model_.parameter_symbols_.back();
      eq.rhs += t.coefficient * symbol * t.value;
      eq.terms.push_back({.coefficient = -t.coefficient,
                          .parameter = static_cast<int>(model_.parameters_.size()) - 1,
                          .monomial = t.monomial,
                          .derivative = -1});
    }
  }
}

void ModelBuilder::add_candidates(const SyntaxNode& n) {
  for (const SyntaxNode& c : n.children) {
    if (c.kind != SyntaxKind::kCandidateName) continue;
    const std::string name(c.text);
    const auto it = std::find_if(model_.parameters_.begin(), model_.parameters_.end(),
                                 [&](const Declaration& d) { return d.name == name; });
    if (it == model_.parameters_.end()) {
      const Declaration* d = symbols_.find(name);
      source_.fail(c, "'" + name + "' is " +
                          (d ? kind_with_article(d->kind) : std::string("not declared")) +
                          ": a candidate is a parameter whose terms selection may drop");
    }
    if (it->fixed) {
      source_.fail(c, "'" + name + "' is fixed (line " + std::to_string(it->where.line) +
                          "): a known parameter cannot be a candidate");
    }
    it->candidate = true;
  }
}

void ModelBuilder::add_multipliers(const SyntaxNode& n) {
  MultiplierSet set;
  set.where = source_.where(n);
  for (const SyntaxNode& c : n.children) {
    if (c.kind == SyntaxKind::kLabel) {
      labels_.check_known(c);
      set.equation = c.text;
    } else if (c.kind == SyntaxKind::kMultiplier) {
      terms_.add_monomial(c, set.monomials);
    }
  }
  model_.multipliers_.push_back(std::move(set));
}

}  // namespace momentid
