#pragma once
// The names a model declares: the declarations themselves, their GiNaC symbols and looking a
// name up in an expression.

#include <ginac/ginac.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "model/syntax.hpp"
#include "momentid/model.hpp"

namespace momentid {

// "a state", "an input", "a parameter" or "a constant", as a message names a declared name.
std::string kind_with_article(SymbolKind kind);

// What a GiNaC symbol of an equation stands for, so that an expanded term can be taken apart
// into its parameter, variable and derivative factors.
struct SymbolRole {
  enum Kind { kParameter, kVariable, kDerivative } kind;
  int index;  // into the parameters, the variables (Model::variables()) or the states
};

// The declarations of one model, in declaration order, and the GiNaC symbols its equations are
// written in. Names are declared first (each once, none of them a reserved word), then
// make_symbols() gives every state, derivative, input and parameter its symbol; only then can an
// expression look names up.
class SymbolTable {
 public:
  explicit SymbolTable(const Source& source) : source_(source) {}
  // The names of an already built model, to read a `--multipliers` list against it.
  SymbolTable(const Source& source, const Model& model);
  // The lookup maps point into the table's own lists.
  SymbolTable(const SymbolTable&) = delete;
  SymbolTable& operator=(const SymbolTable&) = delete;

  // Declares every name of a state, input, param or const statement. A model has at most
  // kMaxVariables states, inputs and measured columns in all (its terms' monomials, and the
  // moments, grow with their count) and kMaxParameters parameters.
  void declare_all(const SyntaxNode& statement, SymbolKind kind);
  static constexpr std::size_t kMaxVariables = 1000;
  static constexpr std::size_t kMaxParameters = 1000;
  // Declares the columns of a `measured` statement; their derivatives are read once the
  // equations are (measured_targets()).
  void declare_measured(const SyntaxNode& statement);
  // Once every name is declared: a name may be used before its declaration.
  void make_symbols();

  // The declaration of `name`, or nullptr.
  const Declaration* find(const std::string& name) const;
  // What `name`, used at `at`, stands for in an expression: its symbol, or a constant's value.
  GiNaC::ex value(const SyntaxNode& at, const std::string& name) const;
  // The symbol of the time derivative of state `name`, used at `at`.
  GiNaC::ex derivative(const SyntaxNode& at, const std::string& name) const;
  // Instruments of a built model may name its measured columns, by name or as the derivative
  // they hold (`v'`, or `y''` through `y' = v`): from then on value() gives a measured column's
  // symbol, and measured_derivative() the column of a derivative.
  void read_measured() { read_measured_ = model_ != nullptr; }
  // The symbol of the measured column that holds derivative `order` of state `name`, or
  // nullopt (also unless read_measured()).
  std::optional<GiNaC::ex> measured_derivative(const std::string& name, std::size_t order) const;
  const SymbolRole& role(const GiNaC::ex& symbol) const { return roles_.at(symbol); }
  // The symbol of `f` (whose name identifies it), a variable after those before it: the first
  // use adds it.
  GiNaC::ex function(const VariableFunction& f);

  const std::vector<Declaration>& states() const { return states_; }
  const std::vector<Declaration>& inputs() const { return inputs_; }
  const std::vector<Declaration>& parameters() const { return parameters_; }
  const std::vector<Declaration>& constants() const { return constants_; }
  const std::vector<Declaration>& measured() const { return measured_; }
  // The `v'` of each measured column, in the order of measured().
  const std::vector<const SyntaxNode*>& measured_targets() const { return measured_targets_; }
  const std::vector<VariableFunction>& functions() const { return functions_; }
  const std::vector<Variable>& variables() const { return variables_; }
  const std::vector<GiNaC::symbol>& state_symbols() const { return state_symbols_; }
  const std::vector<GiNaC::symbol>& derivative_symbols() const { return derivative_symbols_; }
  const std::vector<GiNaC::symbol>& input_symbols() const { return input_symbols_; }
  const std::vector<GiNaC::symbol>& parameter_symbols() const { return parameter_symbols_; }
  const std::vector<GiNaC::symbol>& function_symbols() const { return function_symbols_; }
  const std::vector<GiNaC::symbol>& measured_symbols() const { return measured_symbols_; }

 private:
  // `value_node` is the `= value` part, or nullptr.
  void declare(const SyntaxNode& name_node, const SyntaxNode* value_node, SymbolKind kind,
               bool fixed = false);
  // Fills the lookup maps from the lists.
  void index_symbols();
  // Everything declared, by kind: what an error about an undeclared name offers instead.
  std::string declared_list() const;
  // The declaration of `name`; an undeclared name is an error at `at`.
  const Declaration& lookup(const SyntaxNode& at, const std::string& name) const;
  // The position of `d` in the list of its kind, which is also that of its symbol.
  int index_of(const Declaration& d) const;

  const Source& source_;
  const Model* model_ = nullptr;  // the built model this table reads, if any
  bool read_measured_ = false;
  std::vector<Declaration> states_, inputs_, parameters_, constants_, measured_;
  std::vector<const SyntaxNode*> measured_targets_;
  std::vector<std::string> measured_written_;
  std::vector<VariableFunction> functions_;
  std::vector<Variable> variables_;
  std::vector<GiNaC::symbol> state_symbols_, derivative_symbols_, input_symbols_,
      parameter_symbols_, function_symbols_, measured_symbols_;
  std::map<std::string, const Declaration*> declared_;    // after all declarations are collected
  std::map<std::string, Declaration> first_declaration_;  // while they are
  std::map<GiNaC::ex, SymbolRole, GiNaC::ex_is_less> roles_;
};

}  // namespace momentid
