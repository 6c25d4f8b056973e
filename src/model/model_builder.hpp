#pragma once
// Reads the statements of a parsed model file into a Model.

#include <string>
#include <string_view>
#include <vector>

#include "model/checks.hpp"
#include "model/symbols.hpp"
#include "model/syntax.hpp"
#include "model/terms.hpp"
#include "momentid/model.hpp"

namespace momentid {

// Builds a Model from the parse tree of a model file. It reads the statements in the order that
// decides which problem is reported first: the `model` statement and the declarations in file
// order, then the equations, the `library` and `candidate` statements, the `multipliers`
// statements, then the model as a whole.
// Model befriends it: it is the one place that fills a Model in.
class ModelBuilder {
 public:
  // `text` is what the tree was parsed from and must outlive the builder; `file` names it.
  ModelBuilder(std::string_view text, std::string file);

  // `statements` are the top-level nodes of the tree, in file order.
  Model build(const std::vector<SyntaxNode>& statements);
  // Equations a model may have (each is multiplied by every multiplier).
  static constexpr std::size_t kMaxEquations = 1000;
  // The longest name: a message that names one quotes it whole.
  static constexpr std::size_t kMaxName = 255;

 private:
  // Reads the `model` statement and the declarations, and sets the equations and `multipliers`
  // statements aside until every name is declared.
  void collect(const std::vector<SyntaxNode>& statements);
  void check_name_lengths(const SyntaxNode& n) const;
  void add_equation(const SyntaxNode& n);
  void add_multipliers(const SyntaxNode& n);
  // The terms of a `library` statement, each with a candidate parameter of its own, joined to
  // the right side of the equation it names.
  void add_library(const SyntaxNode& n);
  // The equation a `library` statement's target names: a state's derivative or a label.
  Equation& library_equation(const SyntaxNode& target);
  // Marks the parameters of a `candidate` statement.
  void add_candidates(const SyntaxNode& n);
  // The state whose derivative measured column i holds, once the equations are read (`y''` is
  // v' through y' = v).
  void add_measured(std::size_t i);

  Source source_;
  SymbolTable symbols_;
  TermBuilder terms_;
  EquationLabels labels_;
  Model model_;
  const SyntaxNode* model_statement_ = nullptr;
  std::vector<const SyntaxNode*> equation_nodes_, multiplier_nodes_, library_nodes_,
      candidate_nodes_;
};

}  // namespace momentid
