#include "model/model_builder.hpp"

#include <cctype>

namespace momentid {

ModelBuilder::ModelBuilder(std::string_view text, std::string file)
    : source_(text, file), symbols_(source_), terms_(source_, symbols_), labels_(source_) {
  model_.file_ = std::move(file);
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
  // The equations add the functions they use as variables: only now are they all known, and
  // every monomial gets their exponents.
  model_.functions_ = symbols_.functions();
  model_.function_symbols_ = symbols_.function_symbols();
  model_.variables_ = symbols_.variables();
  for (Equation& eq : model_.equations_) {
    for (Term& t : eq.terms) t.monomial.resize(model_.variables_.size());
  }
  for (const SyntaxNode* m : multiplier_nodes_) add_multipliers(*m);
  check_model(model_, source_);
  return std::move(model_);
}

void ModelBuilder::collect(const std::vector<SyntaxNode>& statements) {
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
    } else if (n.kind == SyntaxKind::kEquation) {
      equation_nodes_.push_back(&n);
    } else if (n.kind == SyntaxKind::kMultipliersStatement) {
      multiplier_nodes_.push_back(&n);
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
