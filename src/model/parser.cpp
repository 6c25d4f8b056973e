// Parses the model language with the PEGTL grammar in grammar/ and checks what the text means.
// This is the only translation unit that includes PEGTL.

#include <Eigen/Dense>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

#include "error_messages.hpp"
#include "momentid/model.hpp"
#include "model_grammar.hpp"
#include "tao/pegtl/contrib/parse_tree.hpp"

namespace momentid {
namespace {

// Limits that keep every model small enough to derive and simulate.
constexpr int kMaxDegree = 64;          // total degree of a term or multiplier
constexpr int kMaxNumberDigits = 2000;  // of a number computed from a power
constexpr int kMaxNesting = 200;        // of parentheses

namespace pegtl = tao::pegtl;
namespace g = grammar;
using Node = pegtl::parse_tree::node;

// The parse-tree nodes kept; every other rule only groups its children.
template <typename Rule>
using Selector = pegtl::parse_tree::selector<
    Rule, pegtl::parse_tree::store_content::on<
              g::model_statement, g::model_name, g::string_body, g::state_declaration,
              g::input_declaration, g::param_declaration, g::const_declaration, g::declared_name,
              g::param_item, g::const_item, g::signed_number, g::number, g::label, g::equation,
              g::lhs, g::rhs, g::multipliers_statement, g::multiplier, g::expression,
              g::term_operand, g::product, g::times, g::divide, g::add, g::subtract, g::unary,
              g::operand, g::minus_sign, g::plus_sign, g::power, g::exponent_operand, g::variable,
              g::name, g::primes, g::dot_call, g::dot_argument, g::call, g::parenthesized>>;

template <typename Rule>
using Control = pegtl::must_if<g::error_messages>::control<Rule>;

// The text of line `line` (from 1) of `source`, without its line break.
std::string line_of(std::string_view source, std::size_t line) {
  std::size_t begin = 0;
  for (std::size_t n = 1; n < line && begin != std::string_view::npos; ++n) {
    begin = source.find('\n', begin);
    if (begin != std::string_view::npos) ++begin;
  }
  if (begin == std::string_view::npos || begin > source.size()) return "";
  std::size_t end = source.find('\n', begin);
  std::string text(source.substr(begin, end == std::string_view::npos ? end : end - begin));
  if (!text.empty() && text.back() == '\r') text.pop_back();
  return text;
}

bool is_sum(const Node& n) {
  return n.is_type<g::lhs>() || n.is_type<g::rhs>() || n.is_type<g::multiplier>() ||
         n.is_type<g::expression>();
}
bool is_product(const Node& n) { return n.is_type<g::product>() || n.is_type<g::term_operand>(); }
bool is_unary(const Node& n) { return n.is_type<g::unary>() || n.is_type<g::operand>(); }

// What a symbol of an equation stands for.
struct SymbolRole {
  enum Kind { kParameter, kVariable, kDerivative } kind;
  int index;
};

// An expanded term split into its factors, exponents indexed like the model's declarations.
struct SplitTerm {
  GiNaC::numeric coefficient;
  std::vector<int> parameters, variables, derivatives;
};

}  // namespace

// Builds a Model from a parse tree, checking meaning as it goes.
class ModelBuilder {
 public:
  ModelBuilder(std::string_view text, std::string file) : text_(text) {
    model_.file_ = std::move(file);
  }

  Model build(const Node& root) {
    collect(root);
    make_symbols();
    for (const Node* eq : equation_nodes_) add_equation(*eq);
    for (const Node* m : multiplier_nodes_) add_multipliers(*m);
    check_whole_model();
    return std::move(model_);
  }

  // Evaluates a `--multipliers` list against an already built model.
  static std::vector<Monomial> multiplier_list(const Model& model, const Node& root,
                                               std::string_view text, const std::string& source) {
    ModelBuilder builder(text, source);
    builder.model_ = model;
    builder.model_.file_ = source;
    builder.index_symbols();
    std::vector<Monomial> out;
    for (const auto& child : root.children) {
      if (child->is_type<g::multiplier>()) builder.add_monomial(*child, out);
    }
    return out;
  }

 private:
  SourceLocation where(const Node& n) const {
    const pegtl::position p = n.begin();
    return {model_.file_, static_cast<int>(p.line), static_cast<int>(p.column),
            line_of(text_, p.line)};
  }
  [[noreturn]] void fail(const Node& n, const std::string& message) const {
    throw ModelError(where(n), message);
  }

  // --- Declarations ---------------------------------------------------------------------------

  void collect(const Node& root) {
    for (const auto& child : root.children) {
      const Node& n = *child;
      if (n.is_type<g::model_statement>()) {
        if (model_statement_ != nullptr) {
          fail(n, "a second 'model' statement (the first is on line " +
                      std::to_string(model_statement_->begin().line) + ")");
        }
        model_statement_ = &n;
        for (const auto& part : n.children) {
          if (part->is_type<g::model_name>()) model_.name_ = part->string();
          if (part->is_type<g::string_body>()) model_.title_ = part->string();
        }
      } else if (n.is_type<g::state_declaration>()) {
        declare_all(n, SymbolKind::kState);
      } else if (n.is_type<g::input_declaration>()) {
        declare_all(n, SymbolKind::kInput);
      } else if (n.is_type<g::param_declaration>()) {
        declare_all(n, SymbolKind::kParameter);
      } else if (n.is_type<g::const_declaration>()) {
        declare_all(n, SymbolKind::kConstant);
      } else if (n.is_type<g::equation>()) {
        equation_nodes_.push_back(&n);
      } else if (n.is_type<g::multipliers_statement>()) {
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

  void declare_all(const Node& statement, SymbolKind kind) {
    for (const auto& child : statement.children) {
      const Node* name = child.get();
      const Node* value = nullptr;
      if (child->is_type<g::param_item>() || child->is_type<g::const_item>()) {
        name = child->children.at(0).get();
        if (child->children.size() > 1) value = child->children[1].get();
      }
      if (!name->is_type<g::declared_name>()) continue;
      declare(*name, value, kind);
    }
  }

  void declare(const Node& name_node, const Node* value_node, SymbolKind kind) {
    const std::string name = name_node.string();
    static const std::set<std::string> reserved{
        "model",     "state",      "states",      "input", "inputs", "param",
        "params",    "parameter",  "parameters",  "const", "consts", "constant",
        "constants", "multiplier", "multipliers", "dot"};
    if (reserved.count(name) != 0) {
      fail(name_node, "'" + name + "' is a reserved word and cannot be declared");
    }
    Declaration d{name, kind, std::nullopt, where(name_node)};
    if (auto [it, fresh] = first_declaration_.emplace(name, d); !fresh) {
      const Declaration& first = it->second;
      fail(name_node, "'" + name + "' is already declared as " + article(first.kind) + " at " +
                          std::to_string(first.where.line) + ":" +
                          std::to_string(first.where.column));
    }
    if (value_node != nullptr) {
      GiNaC::numeric v = 0;
      bool negative = false;
      for (const auto& part : value_node->children) {
        if (part->is_type<g::minus_sign>()) negative = !negative;
        if (part->is_type<g::number>()) v = number(*part);
      }
      d.value = negative ? -v : v;
    }
    std::vector<Declaration>* list = nullptr;
    switch (kind) {
      case SymbolKind::kState:
        list = &model_.states_;
        break;
      case SymbolKind::kInput:
        list = &model_.inputs_;
        break;
      case SymbolKind::kParameter:
        list = &model_.parameters_;
        break;
      case SymbolKind::kConstant:
        list = &model_.constants_;
        break;
    }
    list->push_back(std::move(d));
  }

  static std::string article(SymbolKind kind) {
    return kind == SymbolKind::kInput ? std::string("an input")
                                      : "a " + std::string(kind_name(kind));
  }

  void make_symbols() {
    for (const Declaration& s : model_.states_) {
      model_.state_symbols_.emplace_back(s.name);
      model_.derivative_symbols_.emplace_back(s.name + "'");
      model_.variables_.push_back(s.name);
    }
    for (const Declaration& u : model_.inputs_) {
      model_.input_symbols_.emplace_back(u.name);
      model_.variables_.push_back(u.name);
    }
    for (const Declaration& p : model_.parameters_) model_.parameter_symbols_.emplace_back(p.name);
    index_symbols();
  }

  void index_symbols() {
    declared_.clear();
    roles_.clear();
    for (auto* l : {&model_.states_, &model_.inputs_, &model_.parameters_, &model_.constants_}) {
      for (const Declaration& x : *l) declared_[x.name] = &x;
    }
    const int n = static_cast<int>(model_.states_.size());
    for (int i = 0; i < n; ++i) {
      roles_.emplace(model_.state_symbols_[i], SymbolRole{SymbolRole::kVariable, i});
      roles_.emplace(model_.derivative_symbols_[i], SymbolRole{SymbolRole::kDerivative, i});
    }
    for (std::size_t i = 0; i < model_.inputs_.size(); ++i) {
      roles_.emplace(model_.input_symbols_[i],
                     SymbolRole{SymbolRole::kVariable, n + static_cast<int>(i)});
    }
    for (std::size_t i = 0; i < model_.parameters_.size(); ++i) {
      roles_.emplace(model_.parameter_symbols_[i],
                     SymbolRole{SymbolRole::kParameter, static_cast<int>(i)});
    }
  }

  // "declared: states y, v; inputs x; parameters c, k, eps; constants m"
  std::string declared_list() const {
    std::string out;
    auto add = [&](const char* what, const std::vector<Declaration>& list) {
      if (list.empty()) return;
      if (!out.empty()) out += "; ";
      out += what;
      for (std::size_t i = 0; i < list.size(); ++i) out += (i ? ", " : " ") + list[i].name;
    };
    add("states", model_.states_);
    add("inputs", model_.inputs_);
    add("parameters", model_.parameters_);
    add("constants", model_.constants_);
    return out.empty() ? "nothing is declared" : "declared: " + out;
  }

  const Declaration& lookup(const Node& n, const std::string& name) const {
    auto it = declared_.find(name);
    if (it == declared_.end()) {
      fail(n, "'" + name + "' is not declared (" + declared_list() + ")");
    }
    return *it->second;
  }

  // --- Expressions ----------------------------------------------------------------------------

  GiNaC::ex state_derivative(const Node& at, const std::string& name) const {
    const Declaration& d = lookup(at, name);
    if (d.kind != SymbolKind::kState) {
      fail(at, "cannot take the time derivative of " + article(d.kind) + " '" + name +
                   "': only states have derivatives");
    }
    return model_.derivative_symbols_[index_of(d)];
  }

  int index_of(const Declaration& d) const {
    const std::vector<Declaration>& list = d.kind == SymbolKind::kState       ? model_.states_
                                           : d.kind == SymbolKind::kInput     ? model_.inputs_
                                           : d.kind == SymbolKind::kParameter ? model_.parameters_
                                                                              : model_.constants_;
    return static_cast<int>(&d - list.data());
  }

  GiNaC::ex symbol_value(const Node& at, const std::string& name) const {
    const Declaration& d = lookup(at, name);
    const int i = index_of(d);
    switch (d.kind) {
      case SymbolKind::kState:
        return model_.state_symbols_[i];
      case SymbolKind::kInput:
        return model_.input_symbols_[i];
      case SymbolKind::kParameter:
        return model_.parameter_symbols_[i];
      case SymbolKind::kConstant:
        return *d.value;
    }
    return 0;
  }

  GiNaC::numeric number(const Node& n) const {
    try {
      return parse_exact_number(n.string_view());
    } catch (const std::out_of_range& e) {
      fail(n, e.what());
    }
  }

  GiNaC::ex eval(const Node& n) const {
    if (is_sum(n)) return eval_sum(n, false);
    if (is_product(n)) return eval_product(n);
    if (is_unary(n)) {
      GiNaC::ex value = eval(*n.children.back());
      for (const auto& c : n.children) {
        if (c->is_type<g::minus_sign>()) value = -value;
      }
      return value;
    }
    if (n.is_type<g::power>()) return eval_power(n);
    if (n.is_type<g::number>()) return number(n);
    if (n.is_type<g::parenthesized>()) return eval(*n.children.at(0));
    if (n.is_type<g::variable>()) {
      const std::string name = n.children.at(0)->string();
      if (n.children.size() == 1) return symbol_value(n, name);
      const std::size_t order = n.children[1]->string_view().size();
      GiNaC::ex d = state_derivative(n, name);
      if (order > 1) {
        fail(*n.children[1], "derivatives of order " + std::to_string(order) +
                                 " are not supported: write the model in first-order form, "
                                 "with a state for '" +
                                 name + "''");
      }
      return d;
    }
    if (n.is_type<g::dot_call>()) {
      const Node& arg = *n.children.at(0);
      return state_derivative(arg, arg.string());
    }
    if (n.is_type<g::call>()) {
      const std::string name = n.children.at(0)->string();
      if (auto it = declared_.find(name); it != declared_.end()) {
        fail(n, "'" + name + "' is " + article(it->second->kind) + ", not a function: write '" +
                    name + "*(...)' for a product");
      }
      fail(n, "function '" + name +
                  "' is not allowed: equations are polynomials (the only call is dot(...))");
    }
    fail(n, "unexpected syntax");  // unreachable with the grammar in grammar/
  }

  // `top_level`: each product of the sum is a term of the equation as written, so it is checked
  // for affinity in the parameters and for a single derivative factor.
  GiNaC::ex eval_sum(const Node& n, bool top_level) const {
    GiNaC::ex value = 0;
    bool negate = false;
    for (const auto& c : n.children) {
      if (c->is_type<g::add>()) {
        negate = false;
      } else if (c->is_type<g::subtract>()) {
        negate = true;
      } else {
        GiNaC::ex term = eval(*c);
        if (top_level) check_term(*c, term);
        value += negate ? -term : term;
      }
    }
    return value;
  }

  GiNaC::ex eval_product(const Node& n) const {
    GiNaC::ex value = 1;
    bool divide = false;
    for (const auto& c : n.children) {
      if (c->is_type<g::times>()) {
        divide = false;
      } else if (c->is_type<g::divide>()) {
        divide = true;
      } else {
        GiNaC::ex factor = eval(*c);
        if (!divide) {
          value *= factor;
          check_size(n, value);
          continue;
        }
        if (!GiNaC::is_a<GiNaC::numeric>(factor)) {
          fail(*c, "can only divide by a number, found '" + std::string(c->string_view()) + "'");
        }
        if (GiNaC::ex_to<GiNaC::numeric>(factor).is_zero()) fail(*c, "division by zero");
        value /= factor;
      }
    }
    return value;
  }

  GiNaC::ex eval_power(const Node& n) const {
    GiNaC::ex base = eval(*n.children.at(0));
    if (n.children.size() == 1) return base;
    const Node& operand = *n.children[1];
    GiNaC::ex exponent = eval(*operand.children.back());
    for (const auto& c : operand.children) {
      if (c->is_type<g::minus_sign>()) exponent = -exponent;
    }
    if (!GiNaC::is_a<GiNaC::numeric>(exponent) ||
        !GiNaC::ex_to<GiNaC::numeric>(exponent).is_nonneg_integer()) {
      fail(operand, "the exponent must be a non-negative integer, found '" +
                        std::string(operand.string_view()) + "'");
    }
    if (base.is_zero() && exponent.is_zero()) fail(n, "0^0 is undefined");
    if (exponent > kMaxDegree) {
      fail(operand, "the exponent " + std::string(operand.string_view()) +
                        " is too large (at most " + std::to_string(kMaxDegree) + ")");
    }
    if (GiNaC::is_a<GiNaC::numeric>(base)) {
      const GiNaC::numeric b = GiNaC::ex_to<GiNaC::numeric>(base);
      std::ostringstream numerator, denominator;
      numerator << b.numer();
      denominator << b.denom();
      const double digits =
          static_cast<double>(std::max(numerator.str().size(), denominator.str().size()) - 1) *
          GiNaC::ex_to<GiNaC::numeric>(exponent).to_double();
      if (digits > kMaxNumberDigits) {
        fail(n, "the number is too large (about 1e" + std::to_string(static_cast<long>(digits)) +
                    "; at most 1e" + std::to_string(kMaxNumberDigits) + ")");
      }
    }
    GiNaC::ex value = GiNaC::pow(base, exponent);
    check_size(n, value);
    return value;
  }

  // The highest total degree of any term of `e` in the symbols, without expanding it.
  static int total_degree(const GiNaC::ex& e) {
    if (GiNaC::is_a<GiNaC::symbol>(e)) return 1;
    if (GiNaC::is_a<GiNaC::add>(e)) {
      int d = 0;
      for (const GiNaC::ex& op : e) d = std::max(d, total_degree(op));
      return d;
    }
    if (GiNaC::is_a<GiNaC::mul>(e)) {
      long d = 0;
      for (const GiNaC::ex& op : e) d += total_degree(op);
      return static_cast<int>(std::min<long>(d, 1L << 20));
    }
    if (GiNaC::is_a<GiNaC::power>(e) && GiNaC::is_a<GiNaC::numeric>(e.op(1))) {
      const long d = static_cast<long>(total_degree(e.op(0))) *
                     std::min<long>(GiNaC::ex_to<GiNaC::numeric>(e.op(1)).to_long(), 1L << 20);
      return static_cast<int>(std::min<long>(d, 1L << 20));
    }
    return 0;
  }

  // Keeps terms within what the derivation and the simulator handle: a degree of at most
  // kMaxDegree in all variables, parameters and derivatives together.
  void check_size(const Node& at, const GiNaC::ex& value) const {
    const int degree = total_degree(value);
    if (degree > kMaxDegree) {
      fail(at, "this term has degree " + std::to_string(degree) + ", above the highest allowed (" +
                   std::to_string(kMaxDegree) + ")");
    }
  }

  // --- Terms ----------------------------------------------------------------------------------

  SplitTerm split(const GiNaC::ex& term) const {
    SplitTerm t{1, std::vector<int>(model_.parameters_.size()),
                std::vector<int>(model_.variables_.size()),
                std::vector<int>(model_.states_.size())};
    auto add_factor = [&](const GiNaC::ex& f) {
      if (GiNaC::is_a<GiNaC::numeric>(f)) {
        t.coefficient *= GiNaC::ex_to<GiNaC::numeric>(f);
        return;
      }
      GiNaC::ex base = f;
      int power = 1;
      if (GiNaC::is_a<GiNaC::power>(f)) {
        base = f.op(0);
        power = GiNaC::ex_to<GiNaC::numeric>(f.op(1)).to_int();
      }
      const SymbolRole role = roles_.at(base);
      auto& slot = role.kind == SymbolRole::kParameter  ? t.parameters
                   : role.kind == SymbolRole::kVariable ? t.variables
                                                        : t.derivatives;
      slot[role.index] += power;
    };
    if (GiNaC::is_a<GiNaC::mul>(term)) {
      for (const GiNaC::ex& f : term) add_factor(f);
    } else {
      add_factor(term);
    }
    return t;
  }

  std::vector<SplitTerm> split_all(const GiNaC::ex& expanded) const {
    std::vector<SplitTerm> out;
    if (expanded.is_zero()) return out;
    if (GiNaC::is_a<GiNaC::add>(expanded)) {
      for (const GiNaC::ex& term : expanded) out.push_back(split(term));
    } else {
      out.push_back(split(expanded));
    }
    return out;
  }

  // `c*k*y`, `k^2*y`, `y'*v'`: factors in declaration order.
  std::string format_term(const SplitTerm& t) const {
    std::string out;
    auto factor = [&](const std::string& name, int power) {
      if (power == 0) return;
      if (!out.empty()) out += "*";
      out += name;
      if (power > 1) out.append("^").append(std::to_string(power));
    };
    for (std::size_t i = 0; i < t.parameters.size(); ++i) {
      factor(model_.parameters_[i].name, t.parameters[i]);
    }
    for (std::size_t i = 0; i < t.variables.size(); ++i)
      factor(model_.variables_[i], t.variables[i]);
    for (std::size_t i = 0; i < t.derivatives.size(); ++i) {
      factor(model_.states_[i].name + "'", t.derivatives[i]);
    }
    std::ostringstream c;
    c << t.coefficient;
    if (out.empty()) return c.str();
    if (t.coefficient == -1) return "-" + out;
    if (t.coefficient != 1) return c.str() + "*" + out;
    return out;
  }

  static int total(const std::vector<int>& v) {
    int s = 0;
    for (int x : v) s += x;
    return s;
  }

  void check_term(const Node& at, const GiNaC::ex& value) const {
    for (const SplitTerm& t : split_all(value.expand())) {
      if (total(t.parameters) > 1) {
        fail(at, "term '" + format_term(t) +
                     "' is not affine in the parameters: a term may contain at most one "
                     "parameter factor");
      }
      if (total(t.derivatives) > 1) {
        fail(at, "term '" + format_term(t) + "' has " + std::to_string(total(t.derivatives)) +
                     " derivative factors: a term may contain at most one");
      }
    }
  }

  // --- Equations and multipliers --------------------------------------------------------------

  // GiNaC reports arithmetic it cannot do by exceptions; they become errors at the equation.
  void add_equation(const Node& n) {
    try {
      add_equation_checked(n);
    } catch (const LocatedError&) {
      throw;
    } catch (const std::exception& e) {
      fail(n, std::string("cannot evaluate the equation: ") + e.what());
    }
  }

  void add_equation_checked(const Node& n) {
    Equation eq;
    eq.number = static_cast<int>(model_.equations_.size()) + 1;
    eq.where = where(n);
    for (const auto& c : n.children) {
      if (c->is_type<g::label>()) {
        eq.label = c->string();
        if (auto it = labels_.find(eq.label); it != labels_.end()) {
          fail(*c,
               "label '" + eq.label + "' is already used on line " + std::to_string(it->second));
        }
        labels_[eq.label] = eq.where.line;
      } else if (c->is_type<g::lhs>()) {
        eq.lhs = eval_sum(*c, true);
      } else if (c->is_type<g::rhs>()) {
        eq.rhs = eval_sum(*c, true);
      }
    }
    const GiNaC::ex difference = (eq.lhs - eq.rhs).expand();
    if (difference.is_zero()) fail(n, "the equation reduces to 0 = 0");
    for (const SplitTerm& s : split_all(difference)) {
      // Two terms can combine into one that breaks a rule although no term as written does.
      if (total(s.parameters) > 1 || total(s.derivatives) > 1) check_term(n, difference);
      Term t;
      t.coefficient = s.coefficient;
      t.monomial = s.variables;
      for (std::size_t i = 0; i < s.parameters.size(); ++i) {
        if (s.parameters[i]) t.parameter = static_cast<int>(i);
      }
      for (std::size_t i = 0; i < s.derivatives.size(); ++i) {
        if (s.derivatives[i]) t.derivative = static_cast<int>(i);
      }
      eq.terms.push_back(std::move(t));
    }
    model_.equations_.push_back(std::move(eq));
  }

  void add_monomial(const Node& n, std::vector<Monomial>& out) const {
    try {
      add_monomial_checked(n, out);
    } catch (const LocatedError&) {
      throw;
    } catch (const std::exception& e) {
      fail(n, std::string("cannot evaluate the multiplier: ") + e.what());
    }
  }

  void add_monomial_checked(const Node& n, std::vector<Monomial>& out) const {
    const GiNaC::ex value = eval_sum(n, false).expand();
    const std::vector<SplitTerm> terms = split_all(value);
    const std::string text(n.string_view());
    if (terms.size() != 1 || terms[0].coefficient != 1 || total(terms[0].parameters) != 0 ||
        total(terms[0].derivatives) != 0) {
      fail(n, "a multiplier must be a monomial in the states, such as y or y^2*v, found '" + text +
                  "'");
    }
    const Monomial& m = terms[0].variables;
    for (std::size_t i = model_.states_.size(); i < m.size(); ++i) {
      if (m[i] != 0) {
        fail(n, "multiplier '" + text + "' contains input '" + model_.variables_[i] +
                    "': multipliers are monomials in the states");
      }
    }
    Monomial states(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(model_.states_.size()));
    if (std::find(out.begin(), out.end(), states) == out.end()) out.push_back(states);
  }

  void add_multipliers(const Node& n) {
    MultiplierSet set;
    set.where = where(n);
    for (const auto& c : n.children) {
      if (c->is_type<g::label>()) {
        set.equation = c->string();
        if (labels_.count(set.equation) == 0) {
          std::string known;
          for (const Equation& eq : model_.equations_) {
            if (!eq.label.empty()) known += (known.empty() ? "" : ", ") + eq.label;
          }
          fail(*c,
               "no equation is labelled '" + set.equation + "' (" +
                   (known.empty() ? std::string("no equation has a label") : "labels: " + known) +
                   ")");
        }
      } else if (c->is_type<g::multiplier>()) {
        add_monomial(*c, set.monomials);
      }
    }
    model_.multipliers_.push_back(std::move(set));
  }

  // --- The model as a whole -------------------------------------------------------------------

  void check_whole_model() {
    const SourceLocation start{model_.file_, 1, 1, line_of(text_, 1)};
    if (model_.states_.empty()) {
      throw ModelError(start, "the model declares no states (expected a 'state' statement)");
    }
    if (model_.equations_.empty()) throw ModelError(start, "the model has no equations");

    std::vector<bool> used(model_.parameters_.size(), false);
    for (const Equation& eq : model_.equations_) {
      for (const Term& t : eq.terms) {
        if (t.parameter >= 0) used[t.parameter] = true;
      }
    }
    for (std::size_t i = 0; i < used.size(); ++i) {
      if (!used[i]) {
        throw ModelError(model_.parameters_[i].where,
                         "parameter '" + model_.parameters_[i].name + "' appears in no equation");
      }
    }
    check_derivatives_determined();
  }

  // Every state needs an equation of its own that contains its derivative: a matching between
  // states and equations (augmenting paths; models are small).
  void check_derivatives_determined() {
    const std::size_t n = model_.states_.size();
    std::vector<std::set<int>> contains(n);
    for (std::size_t e = 0; e < model_.equations_.size(); ++e) {
      for (const Term& t : model_.equations_[e].terms) {
        if (t.derivative >= 0) contains[t.derivative].insert(static_cast<int>(e));
      }
    }
    for (std::size_t s = 0; s < n; ++s) {
      if (contains[s].empty()) {
        throw ModelError(model_.states_[s].where,
                         "no equation determines the derivative of state '" +
                             model_.states_[s].name + "' (no equation contains " +
                             model_.states_[s].name + "')");
      }
    }
    std::vector<int> owner(model_.equations_.size(), -1);
    std::function<bool(int, std::vector<bool>&)> augment = [&](int s, std::vector<bool>& seen) {
      for (int e : contains[s]) {
        if (seen[e]) continue;
        seen[e] = true;
        if (owner[e] < 0 || augment(owner[e], seen)) {
          owner[e] = s;
          return true;
        }
      }
      return false;
    };
    for (std::size_t s = 0; s < n; ++s) {
      std::vector<bool> seen(model_.equations_.size(), false);
      if (!augment(static_cast<int>(s), seen)) {
        throw ModelError(model_.states_[s].where,
                         "no equation is left to determine the derivative of state '" +
                             model_.states_[s].name +
                             "': the equations containing it are needed for other states");
      }
    }
    check_derivatives_independent();
  }

  // The equations must be solvable for the derivatives: the matrix of their coefficients
  // (polynomials in states, inputs and parameters) has full column rank for generic values.
  // Evaluated at random points; a rank that is full at any point is full generically.
  void check_derivatives_independent() const {
    const std::size_t n = model_.states_.size();
    const std::size_t m = model_.equations_.size();
    std::mt19937_64 engine(7);
    std::uniform_real_distribution<double> draw(0.5, 1.5);
    for (int attempt = 0; attempt < 3; ++attempt) {
      std::vector<double> variable(model_.variables_.size()), parameter(model_.parameters_.size());
      for (double& x : variable) x = draw(engine);
      for (double& x : parameter) x = draw(engine);
      Eigen::MatrixXd a =
          Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(n));
      for (std::size_t e = 0; e < m; ++e) {
        for (const Term& t : model_.equations_[e].terms) {
          if (t.derivative < 0) continue;
          double value = t.coefficient.to_double();
          if (t.parameter >= 0) value *= parameter[t.parameter];
          for (std::size_t i = 0; i < t.monomial.size(); ++i) {
            value *= std::pow(variable[i], t.monomial[i]);
          }
          a(static_cast<Eigen::Index>(e), t.derivative) += value;
        }
      }
      Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
      lu.setThreshold(1e-9);
      if (lu.rank() == static_cast<Eigen::Index>(n)) return;
    }
    std::string names;
    for (const Declaration& s : model_.states_) names += (names.empty() ? "" : ", ") + s.name;
    throw ModelError(model_.equations_.front().where,
                     "the equations cannot be solved for the derivatives of the states (" + names +
                         "): their coefficients are linearly dependent");
  }

  std::string_view text_;
  Model model_;
  std::map<std::string, const Declaration*> declared_;    // after all declarations are collected
  std::map<std::string, Declaration> first_declaration_;  // while they are
  std::map<GiNaC::ex, SymbolRole, GiNaC::ex_is_less> roles_;
  std::map<std::string, int> labels_;
  const Node* model_statement_ = nullptr;
  std::vector<const Node*> equation_nodes_, multiplier_nodes_;
};

namespace {

// Where to report a parse error. Expressions and lists may continue on the next line, so when
// something required is missing the parser has already skipped line breaks and comments; the
// error then belongs at the end of the last line with content, right after what came before.
SourceLocation error_location(std::string_view text, const std::string& file,
                              const pegtl::position& p) {
  std::size_t end = std::min(p.byte, text.size());
  bool skipped_line = false;
  while (true) {
    while (end > 0 && std::isspace(static_cast<unsigned char>(text[end - 1]))) {
      skipped_line = skipped_line || text[end - 1] == '\n';
      --end;
    }
    if (!skipped_line || end == 0) break;
    const std::size_t newline = text.rfind('\n', end - 1);
    const std::size_t start = newline == std::string_view::npos ? 0 : newline + 1;
    std::size_t content = text.find('#', start);
    if (content == std::string_view::npos || content > end) content = end;
    while (content > start && std::isblank(static_cast<unsigned char>(text[content - 1]))) {
      --content;
    }
    if (content == start) {  // a comment line or a blank line: look further up
      end = start;
      continue;
    }
    const auto line =
        static_cast<std::size_t>(std::count(text.begin(), text.begin() + start, '\n')) + 1;
    return {file, static_cast<int>(line), static_cast<int>(content - start + 1),
            line_of(text, line)};
  }
  return {file, static_cast<int>(p.line), static_cast<int>(p.column), line_of(text, p.line)};
}

// Parentheses nested too deep would exhaust the stack of the recursive parser and evaluator.
void check_nesting(std::string_view text, const std::string& file) {
  int depth = 0;
  std::size_t line = 1, line_start = 0;
  bool comment = false, quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    if (ch == '\n') {
      ++line;
      line_start = i + 1;
      comment = quoted = false;
    } else if (comment) {
      continue;
    } else if (ch == '"') {
      quoted = !quoted;
    } else if (quoted) {
      continue;
    } else if (ch == '#') {
      comment = true;
    } else if (ch == '(' && ++depth > kMaxNesting) {
      throw ParseError(
          {file, static_cast<int>(line), static_cast<int>(i - line_start + 1), line_of(text, line)},
          "parentheses are nested more than " + std::to_string(kMaxNesting) + " deep");
    } else if (ch == ')' && depth > 0) {
      --depth;
    }
  }
}

template <typename Rule>
std::unique_ptr<Node> parse_tree(pegtl::memory_input<>& in, std::string_view text,
                                 const std::string& file) {
  check_nesting(text, file);
  try {
    return pegtl::parse_tree::parse<Rule, Selector, pegtl::nothing, Control>(in);
  } catch (const pegtl::parse_error& e) {
    const pegtl::position& p = e.positions().front();
    if (g::may_follow_line_break(e.message())) {
      throw ParseError(error_location(text, file, p), std::string(e.message()));
    }
    throw ParseError(
        {file, static_cast<int>(p.line), static_cast<int>(p.column), line_of(text, p.line)},
        std::string(e.message()));
  }
}

}  // namespace

const char* kind_name(SymbolKind kind) {
  switch (kind) {
    case SymbolKind::kState:
      return "state";
    case SymbolKind::kInput:
      return "input";
    case SymbolKind::kParameter:
      return "parameter";
    case SymbolKind::kConstant:
      return "constant";
  }
  return "";
}

int Model::parameter_index(std::string_view name) const {
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    if (parameters_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

Model parse_model(std::string_view text, const std::string& file) {
  // A UTF-8 byte order mark, as some editors write, is not part of the model.
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  // The parse tree's positions refer to the input's source name: it must outlive the tree.
  pegtl::memory_input in(text.data(), text.size(), file);
  std::unique_ptr<Node> root = parse_tree<g::model_file>(in, text, file);
  if (!root) throw ParseError({file, 1, 1, line_of(text, 1)}, "expected a model");
  return ModelBuilder(text, file).build(*root);
}

Model parse_model_file(const std::string& path) {
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    throw Error(path + ": cannot read the model file: it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open the model file: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  return parse_model(text.str(), path);
}

std::vector<Monomial> parse_multiplier_list(const Model& model, std::string_view text,
                                            const std::string& source) {
  pegtl::memory_input in(text.data(), text.size(), source);
  std::unique_ptr<Node> root = parse_tree<g::multiplier_option>(in, text, source);
  if (!root) throw ParseError({source, 1, 1, std::string(text)}, "expected multipliers");
  return ModelBuilder::multiplier_list(model, *root, text, source);
}

std::string format_monomial(const Model& model, const Monomial& monomial) {
  std::string out;
  for (std::size_t i = 0; i < monomial.size(); ++i) {
    if (monomial[i] == 0) continue;
    if (!out.empty()) out += "*";
    out += model.variables()[i];
    if (monomial[i] > 1) out.append("^").append(std::to_string(monomial[i]));
  }
  return out.empty() ? "1" : out;
}

GiNaC::numeric parse_exact_number(std::string_view text) {
  std::string digits;
  long scale = 0;  // power of ten
  bool fraction = false;
  std::size_t i = 0;
  for (; i < text.size() && text[i] != 'e' && text[i] != 'E'; ++i) {
    if (text[i] == '.') {
      fraction = true;
      continue;
    }
    digits += text[i];
    if (fraction) --scale;
  }
  if (i < text.size()) {
    ++i;
    bool negative = false;
    if (text[i] == '+' || text[i] == '-') negative = text[i++] == '-';
    long e = 0;
    for (; i < text.size(); ++i) e = std::min<long>(e * 10 + (text[i] - '0'), 1000000);
    scale += negative ? -e : e;
  }
  const std::size_t first = digits.find_first_not_of('0');
  if (first == std::string::npos) return 0;
  digits.erase(0, first);
  // The power of ten of the leading digit decides the range.
  const long magnitude = scale + static_cast<long>(digits.size()) - 1;
  if (magnitude > kMaxDecimalExponent || magnitude < -kMaxDecimalExponent ||
      digits.size() > static_cast<std::size_t>(kMaxDecimalExponent)) {
    throw std::out_of_range(
        "the number '" + std::string(text.substr(0, 40)) + (text.size() > 40 ? "..." : "") +
        "' is out of range (powers of ten from -" + std::to_string(kMaxDecimalExponent) + " to " +
        std::to_string(kMaxDecimalExponent) + " and at most " +
        std::to_string(kMaxDecimalExponent) + " digits are accepted)");
  }
  return GiNaC::numeric(digits.c_str()) * GiNaC::pow(GiNaC::numeric(10), GiNaC::numeric(scale));
}

}  // namespace momentid
