#include "model/terms.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "momentid/derive.hpp"

namespace momentid {
namespace {

// Limits that keep every model small enough to derive and simulate.
constexpr int kMaxDegree = 64;          // total degree of a term or multiplier
constexpr int kMaxNumberDigits = 2000;  // of a number computed from a power

bool is_sum(const SyntaxNode& n) {
  return n.kind == SyntaxKind::kLhs || n.kind == SyntaxKind::kRhs ||
         n.kind == SyntaxKind::kMultiplier || n.kind == SyntaxKind::kLibraryTerm ||
         n.kind == SyntaxKind::kExpression;
}
bool is_product(const SyntaxNode& n) {
  return n.kind == SyntaxKind::kProduct || n.kind == SyntaxKind::kTermOperand;
}
bool is_unary(const SyntaxNode& n) {
  return n.kind == SyntaxKind::kUnary || n.kind == SyntaxKind::kOperand;
}

// The highest total degree of any term of `e` in the symbols, without expanding it.
int total_degree(const GiNaC::ex& e) {
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

int total(const std::vector<int>& v) {
  int s = 0;
  for (int x : v) s += x;
  return s;
}

// The call that expression `n` consists of, with nothing around it, or nullptr.
const SyntaxNode* sole_call(const SyntaxNode& n) {
  const SyntaxNode* at = &n;
  while (at->kind != SyntaxKind::kCall) {
    if (at->children.size() != 1) return nullptr;
    at = &at->children[0];
  }
  return at;
}

}  // namespace

// --- Equations and multipliers ----------------------------------------------------------------

// GiNaC reports arithmetic it cannot do by exceptions; they become errors at node `n`, "cannot
// evaluate the `what`: ...".
template <class Evaluate>
auto TermBuilder::located(const SyntaxNode& n, const char* what, Evaluate evaluate) const {
  try {
    return evaluate();
  } catch (const LocatedError&) {
    throw;
  } catch (const std::exception& e) {
    source_.fail(n, std::string("cannot evaluate the ") + what + ": " + e.what());
  }
}

Equation TermBuilder::equation(const SyntaxNode& n) const {
  return located(n, "equation", [&] { return equation_checked(n); });
}

Equation TermBuilder::equation_checked(const SyntaxNode& n) const {
  Equation eq;
  eq.where = source_.where(n);
  for (const SyntaxNode& c : n.children) {
    if (c.kind == SyntaxKind::kLhs) {
      eq.lhs = eval_sum(c, true);
    } else if (c.kind == SyntaxKind::kRhs) {
      eq.rhs = eval_sum(c, true);
    }
  }
  const GiNaC::ex difference = (eq.lhs - eq.rhs).expand();
  if (difference.is_zero()) source_.fail(n, "the equation reduces to 0 = 0");
  for (const SplitTerm& s : split_all(difference)) {
    // Two terms can combine into one that breaks a rule although no term as written does.
    if (total(s.parameters) > 1 || total(s.derivatives) > 1) check_term(n, difference);
    if (total(s.derivatives) > 0 && function_factor(s)) {
      source_.fail(n, "term '" + format_term(s) +
                          "' multiplies a derivative by abs(...) or sign(...): the moment "
                          "equations can only reduce derivatives times polynomials");
    }
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
  return eq;
}

void TermBuilder::add_monomial(const SyntaxNode& n, std::vector<Monomial>& out, bool inputs) const {
  located(n, "multiplier", [&] { add_monomial_checked(n, out, inputs); });
}

void TermBuilder::add_monomial_checked(const SyntaxNode& n, std::vector<Monomial>& out,
                                       bool inputs) const {
  const GiNaC::ex value = eval_sum(n, false).expand();
  const std::vector<SplitTerm> terms = split_all(value);
  const std::string text(n.text);
  if (terms.size() != 1 || terms[0].coefficient != 1 || total(terms[0].parameters) != 0 ||
      total(terms[0].derivatives) != 0) {
    source_.fail(n, inputs ? "an instrument must be a monomial in the states and inputs, such as "
                             "y or y^3, found '" +
                                 text + "'"
                           : "a multiplier must be a monomial in the states, such as y or y^2*v, "
                             "found '" +
                                 text + "'");
  }
  const Monomial& m = terms[0].variables;
  if (function_factor(terms[0]) && !inputs) {
    source_.fail(n, "a multiplier cannot hold abs(...) or sign(...), found '" + text +
                        "': the stationarity identities need polynomials");
  }
  if (inputs) {
    if (std::find(out.begin(), out.end(), m) == out.end()) out.push_back(m);
    return;
  }
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (m[i] != 0 && symbols_.variables()[i].kind != VariableKind::kState) {
      source_.fail(n, "multiplier '" + text + "' contains input '" + symbols_.variables()[i].name +
                          "': multipliers are monomials in the states");
    }
  }
  Monomial in_states(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(symbols_.states().size()));
  if (std::find(out.begin(), out.end(), in_states) == out.end()) out.push_back(in_states);
}

// --- Library terms ----------------------------------------------------------------------------

std::vector<TermBuilder::LibraryTerm> TermBuilder::library_terms(const SyntaxNode& n) const {
  return located(n, "library term", [&] { return library_terms_checked(n); });
}

std::vector<TermBuilder::LibraryTerm> TermBuilder::library_terms_checked(
    const SyntaxNode& n) const {
  if (const SyntaxNode* call = sole_call(n); call && call->children.at(0).text == "monomials") {
    return generated_terms(*call);
  }
  const GiNaC::ex value = eval_sum(n, false).expand();
  const std::vector<SplitTerm> terms = split_all(value);
  const std::string text(n.text);
  if (terms.size() != 1) {
    source_.fail(n,
                 "a library term is one product of states, inputs, abs(...) and sign(...), "
                 "found " +
                     std::to_string(terms.size()) + " terms in '" + text +
                     "' (write a sum by hand with a 'candidate' parameter)");
  }
  const SplitTerm& t = terms[0];
  if (total(t.parameters) != 0) {
    source_.fail(n, "a library term has no parameter, found '" + text +
                        "': the library gives each term a parameter of its own");
  }
  if (total(t.derivatives) != 0) {
    source_.fail(n, "a library term cannot hold a derivative, found '" + text + "'");
  }
  // The constant is written 1: its parameter is the constant itself (an offset, a static load).
  if (t.variables.degree() == 0 && t.coefficient != 1) {
    source_.fail(
        n, "a constant library term is written 1 (its parameter is the constant), found '" + text +
               "'");
  }
  return {{t.coefficient, t.variables, value / t.coefficient, false}};
}

std::vector<TermBuilder::LibraryTerm> TermBuilder::generated_terms(const SyntaxNode& call) const {
  const std::string usage =
      "monomials(NAME, ..., DEGREE): the monomials of degree 1 to DEGREE in "
      "the states and inputs named";
  if (call.children.size() < 3) source_.fail(call, "expected " + usage);
  std::vector<std::size_t> variables;
  for (std::size_t i = 1; i + 1 < call.children.size(); ++i) {
    const SyntaxNode& argument = call.children[i];
    const SyntaxNode* leaf = &argument;
    while (leaf->children.size() == 1 && leaf->kind != SyntaxKind::kVariable) {
      leaf = &leaf->children[0];
    }
    const std::string name(leaf->text);
    const Declaration* d = leaf->kind == SyntaxKind::kVariable && leaf->children.size() == 1
                               ? symbols_.find(name)
                               : nullptr;
    if (!d || (d->kind != SymbolKind::kState && d->kind != SymbolKind::kInput)) {
      source_.fail(argument, "expected a state or an input in " + usage + ", found '" +
                                 std::string(argument.text) + "'");
    }
    const auto& all = symbols_.variables();
    const auto v = static_cast<std::size_t>(
        std::find_if(all.begin(), all.end(), [&](const Variable& x) { return x.name == name; }) -
        all.begin());
    if (std::find(variables.begin(), variables.end(), v) != variables.end()) {
      source_.fail(argument, "'" + name + "' is named twice in monomials(...)");
    }
    variables.push_back(v);
  }
  const SyntaxNode& last = call.children.back();
  const GiNaC::ex degree_value = eval(last);
  if (!GiNaC::is_a<GiNaC::numeric>(degree_value) ||
      !GiNaC::ex_to<GiNaC::numeric>(degree_value).is_pos_integer() ||
      GiNaC::ex_to<GiNaC::numeric>(degree_value).to_long() > kMaxGeneratedDegree) {
    source_.fail(last, "expected the highest degree, a whole number from 1 to " +
                           std::to_string(kMaxGeneratedDegree) + ", as the last argument of " +
                           usage + ", found '" + std::string(last.text) + "'");
  }
  const int degree = GiNaC::ex_to<GiNaC::numeric>(degree_value).to_int();
  const auto count = static_cast<int>(variables.size());
  if (count_monomials(count, degree) > kMaxGenerated) {
    source_.fail(call, "monomials(...) would make " +
                           std::to_string(static_cast<long>(count_monomials(count, degree))) +
                           " terms, more than " + std::to_string(kMaxGenerated) +
                           ": name fewer variables or a lower degree");
  }
  std::vector<LibraryTerm> out;
  for (const Monomial& e : monomials_up_to(count, degree)) {
    LibraryTerm t{1, Monomial(symbols_.variables().size()), 1, true};
    for (std::size_t i = 0; i < variables.size(); ++i) {
      t.monomial[variables[i]] = e[i];
      t.value *= GiNaC::pow(symbols_.value(call, symbols_.variables()[variables[i]].name), e[i]);
    }
    out.push_back(std::move(t));
  }
  return out;
}

// --- Expressions ------------------------------------------------------------------------------

GiNaC::ex TermBuilder::eval(const SyntaxNode& n) const {
  if (is_sum(n)) return eval_sum(n, false);
  if (is_product(n)) return eval_product(n);
  if (is_unary(n)) {
    GiNaC::ex value = eval(n.children.back());
    for (const SyntaxNode& c : n.children) {
      if (c.kind == SyntaxKind::kMinusSign) value = -value;
    }
    return value;
  }
  if (n.kind == SyntaxKind::kPower) return eval_power(n);
  if (n.kind == SyntaxKind::kNumber) return source_.number(n);
  if (n.kind == SyntaxKind::kParenthesized) return eval(n.children.at(0));
  if (n.kind == SyntaxKind::kVariable) {
    const std::string name(n.children.at(0).text);
    if (n.children.size() == 1) return symbols_.value(n, name);
    const std::size_t order = n.children[1].text.size();
    if (std::optional<GiNaC::ex> column = symbols_.measured_derivative(name, order)) {
      return *column;
    }
    GiNaC::ex d = symbols_.derivative(n, name);
    if (order > 1) {
      source_.fail(n.children[1], "derivatives of order " + std::to_string(order) +
                                      " are not supported: write the model in first-order form, "
                                      "with a state for '" +
                                      name + "''");
    }
    return d;
  }
  if (n.kind == SyntaxKind::kDotCall) {
    const SyntaxNode& arg = n.children.at(0);
    if (std::optional<GiNaC::ex> column = symbols_.measured_derivative(std::string(arg.text), 1)) {
      return *column;
    }
    return symbols_.derivative(arg, std::string(arg.text));
  }
  if (n.kind == SyntaxKind::kCall) return eval_call(n);
  source_.fail(n, "unexpected syntax");  // unreachable with the grammar in grammar/
}

GiNaC::ex TermBuilder::eval_call(const SyntaxNode& n) const {
  const std::string name(n.children.at(0).text);
  if (const Declaration* d = symbols_.find(name); d != nullptr) {
    source_.fail(n, "'" + name + "' is " + kind_with_article(d->kind) +
                        ", not a function: write '" + name + "*(...)' for a product");
  }
  if (name != "abs" && name != "sign") {
    source_.fail(n, "function '" + name +
                        "' is not allowed: equations are polynomials, with abs(...) and "
                        "sign(...) of a polynomial in the states and inputs (and dot(...))");
  }
  if (n.children.size() != 2) {
    source_.fail(n, name + " takes one argument, found " + std::to_string(n.children.size() - 1));
  }
  const SyntaxNode& argument = n.children[1];
  const GiNaC::ex value = eval(argument).expand();
  std::vector<std::pair<GiNaC::numeric, Monomial>> terms;
  const auto channels = static_cast<std::ptrdiff_t>(
      symbols_.states().size() + symbols_.inputs().size() + symbols_.measured().size());
  for (const SplitTerm& t : split_all(value)) {
    if (total(t.parameters) > 0) {
      source_.fail(argument, "a parameter inside " + name +
                                 "(...) would make the term nonlinear in it: write it as a "
                                 "factor outside, as in c*" +
                                 name + "(v)");
    }
    if (total(t.derivatives) > 0) {
      source_.fail(argument, "a derivative cannot be inside " + name + "(...)");
    }
    if (function_factor(t)) source_.fail(argument, "abs(...) and sign(...) cannot be nested");
    terms.emplace_back(t.coefficient,
                       Monomial(t.variables.begin(), t.variables.begin() + channels));
  }
  const bool is_abs = name == "abs";
  if (terms.size() <= 1 && (terms.empty() || terms[0].second.degree() == 0)) {
    const GiNaC::numeric c = terms.empty() ? GiNaC::numeric(0) : terms[0].first;
    return is_abs ? GiNaC::abs(c) : GiNaC::numeric(c.csgn());
  }
  // Highest degree first, the first coefficient 1: abs(-2*v) is 2*abs(v), sign(-2*v) -sign(v).
  std::sort(terms.begin(), terms.end(), [](const auto& a, const auto& b) {
    const int da = a.second.degree(), db = b.second.degree();
    return da != db ? da > db : a.second > b.second;
  });
  const GiNaC::numeric lead = terms[0].first;
  for (auto& [coefficient, monomial] : terms) coefficient /= lead;
  VariableFunction f{is_abs ? FunctionKind::kAbs : FunctionKind::kSign, terms, "",
                     source_.where(n)};
  f.name = name + "(" + format_polynomial(terms) + ")";
  const GiNaC::numeric factor = is_abs ? GiNaC::abs(lead) : GiNaC::numeric(lead.csgn());
  return factor * symbols_.function(f);
}

// `y - 1/2`, `y^2*x + 2*v`: the terms in order, monomials written in the variables' names.
std::string TermBuilder::format_polynomial(
    const std::vector<std::pair<GiNaC::numeric, Monomial>>& terms) const {
  std::string out;
  for (const auto& [coefficient, monomial] : terms) {
    std::string factors;
    for (std::size_t i = 0; i < monomial.size(); ++i) {
      if (monomial[i] == 0) continue;
      if (!factors.empty()) factors += "*";
      factors += symbols_.variables()[i].name;
      if (monomial[i] > 1) {
        factors += "^";
        factors += std::to_string(monomial[i]);
      }
    }
    const GiNaC::numeric size = GiNaC::abs(coefficient);
    std::ostringstream number;
    number << size;
    std::string term = factors.empty() ? number.str()
                       : size == 1     ? factors
                                       : number.str() + "*" + factors;
    if (out.empty()) {
      out = (coefficient < 0 ? "-" : "") + term;
    } else {
      out += (coefficient < 0 ? " - " : " + ") + term;
    }
  }
  return out;
}

bool TermBuilder::function_factor(const SplitTerm& t) const {
  return holds_function(symbols_.variables(), t.variables);
}

// `top_level`: each product of the sum is a term of the equation as written, so it is checked
// for affinity in the parameters and for a single derivative factor.
GiNaC::ex TermBuilder::eval_sum(const SyntaxNode& n, bool top_level) const {
  GiNaC::ex value = 0;
  bool negate = false;
  for (const SyntaxNode& c : n.children) {
    if (c.kind == SyntaxKind::kAdd) {
      negate = false;
    } else if (c.kind == SyntaxKind::kSubtract) {
      negate = true;
    } else {
      GiNaC::ex term = eval(c);
      if (top_level) check_term(c, term);
      value += negate ? -term : term;
    }
  }
  return value;
}

GiNaC::ex TermBuilder::eval_product(const SyntaxNode& n) const {
  GiNaC::ex value = 1;
  bool divide = false;
  for (const SyntaxNode& c : n.children) {
    if (c.kind == SyntaxKind::kTimes) {
      divide = false;
    } else if (c.kind == SyntaxKind::kDivide) {
      divide = true;
    } else {
      GiNaC::ex factor = eval(c);
      if (!divide) {
        value *= factor;
        check_size(n, value);
        continue;
      }
      if (!GiNaC::is_a<GiNaC::numeric>(factor)) {
        source_.fail(c, "can only divide by a number, found '" + std::string(c.text) + "'");
      }
      if (GiNaC::ex_to<GiNaC::numeric>(factor).is_zero()) source_.fail(c, "division by zero");
      value /= factor;
    }
  }
  return value;
}

GiNaC::ex TermBuilder::eval_power(const SyntaxNode& n) const {
  GiNaC::ex base = eval(n.children.at(0));
  if (n.children.size() == 1) return base;
  const SyntaxNode& operand = n.children[1];
  GiNaC::ex exponent = eval(operand.children.back());
  for (const SyntaxNode& c : operand.children) {
    if (c.kind == SyntaxKind::kMinusSign) exponent = -exponent;
  }
  if (!GiNaC::is_a<GiNaC::numeric>(exponent) ||
      !GiNaC::ex_to<GiNaC::numeric>(exponent).is_nonneg_integer()) {
    source_.fail(operand, "the exponent must be a non-negative integer, found '" +
                              std::string(operand.text) + "'");
  }
  if (base.is_zero() && exponent.is_zero()) source_.fail(n, "0^0 is undefined");
  if (exponent > kMaxDegree) {
    source_.fail(operand, "the exponent " + std::string(operand.text) + " is too large (at most " +
                              std::to_string(kMaxDegree) + ")");
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
      source_.fail(n, "the number is too large (about 1e" +
                          std::to_string(static_cast<long>(digits)) + "; at most 1e" +
                          std::to_string(kMaxNumberDigits) + ")");
    }
  }
  GiNaC::ex value = GiNaC::pow(base, exponent);
  check_size(n, value);
  return value;
}

// Keeps terms within what the derivation and the simulator handle: a degree of at most
// kMaxDegree in all variables, parameters and derivatives together.
void TermBuilder::check_size(const SyntaxNode& at, const GiNaC::ex& value) const {
  const int degree = total_degree(value);
  if (degree > kMaxDegree) {
    source_.fail(at, "this term has degree " + std::to_string(degree) +
                         ", above the highest allowed (" + std::to_string(kMaxDegree) + ")");
  }
}

// --- Terms ------------------------------------------------------------------------------------

TermBuilder::SplitTerm TermBuilder::split(const GiNaC::ex& term) const {
  SplitTerm t{1, std::vector<int>(symbols_.parameters().size()),
              Monomial(symbols_.variables().size()), std::vector<int>(symbols_.states().size())};
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
    const SymbolRole role = symbols_.role(base);
    if (role.kind == SymbolRole::kVariable) {
      t.variables[role.index] += power;
    } else {
      (role.kind == SymbolRole::kParameter ? t.parameters : t.derivatives)[role.index] += power;
    }
  };
  if (GiNaC::is_a<GiNaC::mul>(term)) {
    for (const GiNaC::ex& f : term) add_factor(f);
  } else {
    add_factor(term);
  }
  return t;
}

std::vector<TermBuilder::SplitTerm> TermBuilder::split_all(const GiNaC::ex& expanded) const {
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
std::string TermBuilder::format_term(const SplitTerm& t) const {
  std::string out;
  auto factor = [&](const std::string& name, int power) {
    if (power == 0) return;
    if (!out.empty()) out += "*";
    out += name;
    if (power > 1) out.append("^").append(std::to_string(power));
  };
  for (std::size_t i = 0; i < t.parameters.size(); ++i) {
    factor(symbols_.parameters()[i].name, t.parameters[i]);
  }
  for (std::size_t i = 0; i < t.variables.size(); ++i) {
    factor(symbols_.variables()[i].name, t.variables[i]);
  }
  for (std::size_t i = 0; i < t.derivatives.size(); ++i) {
    factor(symbols_.states()[i].name + "'", t.derivatives[i]);
  }
  std::ostringstream c;
  c << t.coefficient;
  if (out.empty()) return c.str();
  if (t.coefficient == -1) return "-" + out;
  if (t.coefficient != 1) return c.str() + "*" + out;
  return out;
}

void TermBuilder::check_term(const SyntaxNode& at, const GiNaC::ex& value) const {
  for (const SplitTerm& t : split_all(value.expand())) {
    if (total(t.parameters) > 1) {
      source_.fail(at, "term '" + format_term(t) +
                           "' is not affine in the parameters: a term may contain at most one "
                           "parameter factor");
    }
    if (total(t.derivatives) > 1) {
      source_.fail(at, "term '" + format_term(t) + "' has " + std::to_string(total(t.derivatives)) +
                           " derivative factors: a term may contain at most one");
    }
  }
}

}  // namespace momentid
