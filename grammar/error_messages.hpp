#pragma once
// What the parser reports when a `must<>` rule of grammar/model_grammar.hpp fails: the text after
// "file:line:col: ". Only src/model/parser.cpp includes this header.

#include "model_grammar.hpp"

namespace momentid::grammar {

template <typename Rule>
inline constexpr const char* error_message = nullptr;

// clang-format off
template <> inline constexpr const char* error_message<exponent_digits> = "expected digits after the exponent mark of a number";
template <> inline constexpr const char* error_message<number> = "expected a number";
template <> inline constexpr const char* error_message<signed_number> = "expected a number";
template <> inline constexpr const char* error_message<string_close> = "expected '\"' to close the title on the same line";
template <> inline constexpr const char* error_message<open_paren> = "expected '(' after dot";
template <> inline constexpr const char* error_message<dot_argument> = "expected a state name inside dot(...)";
template <> inline constexpr const char* error_message<close_paren> = "expected ')'";
template <> inline constexpr const char* error_message<expression> = "expected an expression";
template <> inline constexpr const char* error_message<exponent_operand> = "expected an exponent after '^'";
template <> inline constexpr const char* error_message<operand> = "expected an operand after the operator";
template <> inline constexpr const char* error_message<term_operand> = "expected a term after the operator";
template <> inline constexpr const char* error_message<model_name> = "expected a model name after 'model'";
template <> inline constexpr const char* error_message<declared_value> = "expected '= value'";
template <> inline constexpr const char* error_message<required_value> = "expected '= value': a constant needs a value";
template <> inline constexpr const char* error_message<name_list> = "expected a comma-separated list of names";
template <> inline constexpr const char* error_message<param_list> = "expected a comma-separated list of parameters, each optionally '= value'";
template <> inline constexpr const char* error_message<const_list> = "expected a comma-separated list of constants, each '= value'";
template <> inline constexpr const char* error_message<equals> = "expected '=' of an equation, or a statement keyword (model, state, input, param, const, multipliers)";
template <> inline constexpr const char* error_message<rhs> = "expected the right side of the equation after '='";
template <> inline constexpr const char* error_message<multiplier_list> = "expected a comma-separated list of multipliers (monomials in the states)";
template <> inline constexpr const char* error_message<statement_end> = "expected an operator or the end of the line";
template <> inline constexpr const char* error_message<line> = "expected a statement: model, state, input, param, const, multipliers or an equation";
template <> inline constexpr const char* error_message<list_end> = "expected ',' or the end of the multiplier list";
// clang-format on

// The error table for tao::pegtl::must_if: only a failing `must<>` raises; a rule with a
// message that fails elsewhere (inside `sor<>`, `opt<>`) just backtracks.
struct error_messages {
  template <typename Rule>
  static constexpr bool raise_on_failure = false;
  template <typename Rule>
  static constexpr const char* message = error_message<Rule>;
};

}  // namespace momentid::grammar
