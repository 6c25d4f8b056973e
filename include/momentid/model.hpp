#pragma once

#include <ginac/ginac.h>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "momentid/algebra_lock.hpp"
#include "momentid/error.hpp"
#include "momentid/moment.hpp"

namespace momentid {

enum class SymbolKind { kState, kInput, kParameter, kConstant, kMeasured };

// "state", "input", "parameter", "constant" or "measured column".
const char* kind_name(SymbolKind kind);

// One declared name. `value` is the nominal value of a parameter (optional; the simulator uses
// it) or the value of a constant (always present). Numbers are kept exact: `0.1` is 1/10. A
// parameter declared `fixed` (`param m = 2 fixed`) is known: identify uses its value instead of
// estimating it. A candidate parameter (`candidate eps`, or one a `library` statement made) is
// one whose terms term selection may drop (docs/cli/select.md).
struct Declaration {
  std::string name;
  SymbolKind kind = SymbolKind::kState;
  std::optional<GiNaC::numeric> value;
  SourceLocation where;
  bool fixed = false;
  bool candidate = false;
};

// A factor of a term that is not a power of a state or input: |p| or sign(p) (sign(0) = 0) of
// a polynomial p in the states and inputs, as in `c2*abs(v)*v` (drag), `f*sign(v)` (Coulomb
// friction) or `kc*abs(y - g)` (a stop). Monomials give its exponent after the states and
// inputs (Model::variables()); its moments are data moments like any other, while multipliers
// and the stationarity identities stay polynomial.
enum class FunctionKind { kAbs, kSign };
struct VariableFunction {
  FunctionKind kind = FunctionKind::kAbs;
  // p as coefficient * monomial over the states and inputs, highest degree first, the first
  // coefficient 1.
  std::vector<std::pair<GiNaC::numeric, Monomial>> argument;
  std::string name;      // as formulas write it: "abs(v)", "sign(y - 1/2)"
  SourceLocation where;  // of its first use
};

// A `measured a = v'` statement: a record's column holds the time derivative of a state, as an
// accelerometer's does when v is a velocity (`measured a = y''` says the same when y' = v).
// Equations keep writing v'; where a moment or cross-moment needs E[g*v'], it is read from the
// column instead of being eliminated.
struct MeasuredDerivative {
  std::string name;
  int state = 0;        // whose first derivative the column holds
  std::string written;  // the derivative as the statement writes it: "v'", "y''"
  SourceLocation where;
};

// What a variable of the monomials is. A record has a column for each state, input and measured
// derivative (Variable::channel()), while a function's values are computed from the columns its
// argument holds.
enum class VariableKind { kState, kInput, kDerivative, kFunction };

// A variable of the monomials (Model::variables()): `index` is its position among the model's
// states(), inputs(), measured_derivatives() or functions(), by its kind.
struct Variable {
  std::string name;
  VariableKind kind = VariableKind::kState;
  int index = 0;

  // A record has a column for it.
  bool channel() const { return kind != VariableKind::kFunction; }

  friend bool operator==(const Variable&, const Variable&) = default;
};

// One term of an equation moved to the form `lhs - rhs = 0` and expanded:
// coefficient * parameter * monomial * derivative, where the parameter and the derivative factor
// are optional. The model language guarantees at most one of each.
struct Term {
  GiNaC::numeric coefficient;
  int parameter = -1;   // index into Model::parameters(), or -1
  Monomial monomial;    // over Model::variables()
  int derivative = -1;  // index of the state whose time derivative is a factor, or -1
  // Time derivatives taken of the whole term: d^order/dt^order (y^3) in an equation with latent
  // states eliminated (latent.hpp), which only the lagged equations read; 0 in a model as parsed.
  int order = 0;
};

// One equation of a model, `lhs = rhs`. Constants are already replaced by their values.
struct Equation {
  std::string label;  // as written before ':', or empty
  int number = 0;     // position among the model's equations, from 1
  GiNaC::ex lhs;
  GiNaC::ex rhs;
  std::vector<Term> terms;  // of lhs - rhs
  SourceLocation where;

  // The label if there is one, otherwise the number.
  std::string name() const { return label.empty() ? std::to_string(number) : label; }
};

// A parameter-free equation c1*s' + c2*w = 0 with w a state (y' = v): s' = ratio*w.
struct Kinematic {
  const Equation* equation = nullptr;
  int state = 0;  // w
  GiNaC::numeric ratio;
};

// A `multipliers` statement: monomials in the states by which to multiply one labelled equation,
// or every equation when `equation` is empty.
struct MultiplierSet {
  std::string equation;
  std::vector<Monomial> monomials;
  SourceLocation where;
};

struct Elimination;

// A model read from the model language (grammar/README.md) and checked for meaning: every name
// declared once, equations polynomial in the states, inputs, derivatives and functions
// (VariableFunction), each term affine in
// the parameters and with at most one derivative factor, every state's derivative determined.
//
// Example:
//   Model model = parse_model_file("models/duffing.mom");
//   for (const Equation& eq : model.equations()) std::cout << eq.lhs << " = " << eq.rhs << "\n";
class Model {
 public:
  const std::string& name() const { return name_; }
  const std::string& title() const { return title_; }
  const std::string& file() const { return file_; }

  const std::vector<Declaration>& states() const { return states_; }
  const std::vector<Declaration>& inputs() const { return inputs_; }
  const std::vector<Declaration>& parameters() const { return parameters_; }
  const std::vector<Declaration>& constants() const { return constants_; }
  // The functions of the states and inputs that the equations hold, in order of appearance.
  const std::vector<VariableFunction>& functions() const { return functions_; }
  // The function that a variable of kind kFunction is.
  const VariableFunction& function_of(const Variable& variable) const {
    return functions_[static_cast<std::size_t>(variable.index)];
  }
  // The columns that hold derivatives of states, in order of declaration.
  const std::vector<MeasuredDerivative>& measured_derivatives() const { return measured_; }
  // The index into variables() of the column that holds state i's derivative, or -1.
  int measured_derivative_of(int state) const;
  // The kinematic equation that gives state s's derivative as another state, if any.
  std::optional<Kinematic> kinematic(int s) const;
  // The state whose kinematic equation gives its derivative as state w (y for v when y' = v),
  // or -1.
  int integral_of(int w) const;
  // The model file's text, as parsed.
  const std::string& text() const { return text_; }
  // The variables that monomials are written in: states, then inputs, then measured derivatives,
  // then functions.
  const std::vector<Variable>& variables() const { return variables_; }
  // The variables that a record has columns for (Variable::channel()): the states, inputs and
  // measured derivatives.
  std::size_t channel_count() const { return states_.size() + inputs_.size() + measured_.size(); }
  // Their names, in the order of variables().
  std::vector<std::string> channel_names() const;

  const std::vector<Equation>& equations() const { return equations_; }
  const std::vector<MultiplierSet>& multipliers() const { return multipliers_; }

  // The GiNaC symbols the equations are written in.
  const GiNaC::symbol& state_symbol(int i) const { return state_symbols_[i]; }
  const GiNaC::symbol& derivative_symbol(int i) const { return derivative_symbols_[i]; }
  const GiNaC::symbol& input_symbol(int i) const { return input_symbols_[i]; }
  const GiNaC::symbol& parameter_symbol(int i) const { return parameter_symbols_[i]; }
  const GiNaC::symbol& function_symbol(int i) const { return function_symbols_[i]; }
  const GiNaC::symbol& measured_symbol(int i) const { return measured_symbols_[i]; }
  // The symbol of variables()[v]: a state's, an input's, a measured derivative's or a function's.
  const GiNaC::symbol& variable_symbol(std::size_t v) const {
    const Variable& variable = variables_[v];
    const auto i = static_cast<std::size_t>(variable.index);
    switch (variable.kind) {
      case VariableKind::kState:
        return state_symbols_[i];
      case VariableKind::kInput:
        return input_symbols_[i];
      case VariableKind::kDerivative:
        return measured_symbols_[i];
      case VariableKind::kFunction:
        break;
    }
    return function_symbols_[i];
  }

  // Index of a parameter by name, or -1.
  int parameter_index(std::string_view name) const;
  // Index into variables() by name, or -1.
  int variable_index(std::string_view name) const;

 private:
  friend class ModelBuilder;
  friend Model coefficient_model(const Model& model, const Elimination& elimination);
  detail::AlgebraSpanStart algebra_start_;  // copies and destruction hold the AlgebraLock
  std::string name_, title_, file_, text_;
  std::vector<Declaration> states_, inputs_, parameters_, constants_;
  std::vector<VariableFunction> functions_;
  std::vector<MeasuredDerivative> measured_;
  std::vector<Variable> variables_;
  std::vector<Equation> equations_;
  std::vector<MultiplierSet> multipliers_;
  std::vector<GiNaC::symbol> state_symbols_, derivative_symbols_, input_symbols_,
      parameter_symbols_, function_symbols_, measured_symbols_;
  detail::AlgebraSpanEnd algebra_end_;
};

// How a monomial over Model::variables() changes when every state, input and measured derivative
// changes sign:
// kOdd, it changes sign (its moment vanishes for a symmetric system under a symmetric input);
// kEven, it does not; kNone, neither (abs(p) or sign(p) of a p with terms of both parities,
// such as abs(y - 1)).
enum class Parity { kEven, kOdd, kNone };
Parity parity(const Model& model, const Monomial& monomial);

// Whether a monomial over `variables` has a factor that is a function (abs or sign) of others.
bool holds_function(const std::vector<Variable>& variables, const Monomial& monomial);

// Reads and checks a model file. Throws ParseError or ModelError naming file, line and column,
// or Error when the file cannot be read.
Model parse_model_file(const std::string& path);

// The same for a model held in memory; `file` is the name used in messages.
Model parse_model(std::string_view text, const std::string& file);

// The longest model text read (1 MiB; the longest model shipped is 2 kB): a longer one is a
// ParseError at the byte past it, before any parsing.
inline constexpr std::size_t kMaxModelBytes = std::size_t{1} << 20;

// Parses a comma-separated list of monomials in the model's states, as given to
// `--multipliers`. `source` names the list in messages (e.g. "--multipliers").
std::vector<Monomial> parse_multiplier_list(const Model& model, std::string_view text,
                                            const std::string& source);
// The same for instruments of the lagged equations (`--instruments`): monomials over the states
// and inputs, e.g. "y, y^3, x".
std::vector<Monomial> parse_instrument_list(const Model& model, std::string_view text,
                                            const std::string& source);

// Writes a monomial as `y1^2*y2*x` (factors in declaration order), or `1`.
std::string format_monomial(const Model& model, const Monomial& monomial);

// Parses a decimal number (`4`, `.5`, `1.5e-3`) exactly, as a rational. Throws
// std::out_of_range when its power of ten is beyond kMaxDecimalExponent either way.
GiNaC::numeric parse_exact_number(std::string_view text);
inline constexpr long kMaxDecimalExponent = 1000;

}  // namespace momentid
