#pragma once
// From parsed expressions to what the method works with: GiNaC expressions with constants
// substituted, the terms of an equation, and multipliers as monomials.

#include <ginac/ginac.h>

#include <string>
#include <vector>

#include "model/symbols.hpp"
#include "model/syntax.hpp"
#include "momentid/model.hpp"

namespace momentid {

// Evaluates the expressions of equations and multipliers and refuses those the moment method
// cannot use: anything that is not a polynomial (apart from abs and sign of a polynomial in the
// states and inputs, VariableFunction), terms that are not affine in the parameters or have more
// than one derivative factor, and degrees or numbers beyond the limits that keep a
// model small enough to derive and simulate. Every refusal names the place in the source.
class TermBuilder {
 public:
  // `symbols` gains the functions (abs, sign) the expressions use.
  TermBuilder(const Source& source, SymbolTable& symbols) : source_(source), symbols_(symbols) {}

  // The two sides of equation `n` and the terms of lhs - rhs; the caller sets label and number.
  Equation equation(const SyntaxNode& n) const;
  // Adds multiplier `n`, a monomial in the states (with `inputs`: in the states and inputs, as
  // an instrument), to `out` unless it is there already.
  void add_monomial(const SyntaxNode& n, std::vector<Monomial>& out, bool inputs = false) const;

  // A term of a `library` statement: a number times a product of variables (states, inputs,
  // functions), its value and whether a `monomials(...)` call made it rather than the text.
  struct LibraryTerm {
    GiNaC::numeric coefficient;
    Monomial monomial;  // over the variables known so far
    GiNaC::ex value;
    bool generated = false;
  };
  // The terms that library item `n` stands for: itself, or for `monomials(y, v, 3)` every
  // monomial of degree 1 to 3 in the states and inputs named.
  std::vector<LibraryTerm> library_terms(const SyntaxNode& n) const;
  // The most terms one `monomials(...)` call may make, and its highest degree.
  static constexpr std::size_t kMaxGenerated = 200;
  static constexpr int kMaxGeneratedDegree = 9;

 private:
  // An expanded term taken apart into its factors, exponents indexed like the declarations.
  struct SplitTerm {
    GiNaC::numeric coefficient;
    std::vector<int> parameters;
    Monomial variables;
    std::vector<int> derivatives;
  };

  // `evaluate()`, its exceptions other than located errors turned into errors at `n`.
  template <class Evaluate>
  auto located(const SyntaxNode& n, const char* what, Evaluate evaluate) const;
  // equation(), add_monomial() and library_terms() without turning GiNaC's exceptions into
  // located errors.
  Equation equation_checked(const SyntaxNode& n) const;
  void add_monomial_checked(const SyntaxNode& n, std::vector<Monomial>& out, bool inputs) const;
  std::vector<LibraryTerm> library_terms_checked(const SyntaxNode& n) const;
  std::vector<LibraryTerm> generated_terms(const SyntaxNode& call) const;

  // The value of an expression node, with constants replaced by their values.
  GiNaC::ex eval(const SyntaxNode& n) const;
  GiNaC::ex eval_sum(const SyntaxNode& n, bool top_level) const;
  GiNaC::ex eval_product(const SyntaxNode& n) const;
  GiNaC::ex eval_power(const SyntaxNode& n) const;
  // abs(p) or sign(p) as a number times the symbol of the function of p in canonical form.
  GiNaC::ex eval_call(const SyntaxNode& n) const;
  void check_size(const SyntaxNode& at, const GiNaC::ex& value) const;

  // One term of an expanded expression, or every term of it, taken apart.
  SplitTerm split(const GiNaC::ex& term) const;
  std::vector<SplitTerm> split_all(const GiNaC::ex& expanded) const;
  // Whether the term has a function factor (abs or sign).
  bool function_factor(const SplitTerm& t) const;
  // A function's argument as its name shows it.
  std::string format_polynomial(
      const std::vector<std::pair<GiNaC::numeric, Monomial>>& terms) const;
  // The term as a message shows it.
  std::string format_term(const SplitTerm& t) const;
  // Every term of `value` must be affine in the parameters and have at most one derivative
  // factor; a term that is not is reported at `at`.
  void check_term(const SyntaxNode& at, const GiNaC::ex& value) const;

  const Source& source_;
  SymbolTable& symbols_;
};

}  // namespace momentid
