#pragma once
// What the parser reports when a `must<>` rule of grammar/model_grammar.hpp fails: the text after
// "file:line:col: ". Only src/model/parser.cpp includes this header.

#include <string_view>

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
template <> inline constexpr const char* error_message<closing_paren> = "expected ')'";
template <> inline constexpr const char* error_message<expression_in_parens> = "expected an expression after '('";
template <> inline constexpr const char* error_message<exponent_after_operator> = "expected an exponent after '^'";
template <> inline constexpr const char* error_message<operand_after_operator> = "expected an operand after the operator";
template <> inline constexpr const char* error_message<term_after_operator> = "expected a term after the operator";
template <> inline constexpr const char* error_message<model_name> = "expected a model name after 'model'";
template <> inline constexpr const char* error_message<declared_value> = "expected '= value'";
template <> inline constexpr const char* error_message<required_value> = "expected '= value': a constant needs a value";
template <> inline constexpr const char* error_message<item_after_comma<declared_name>> = "expected a name after ','";
template <> inline constexpr const char* error_message<item_after_comma<param_item>> = "expected a parameter name after ','";
template <> inline constexpr const char* error_message<item_after_comma<const_item>> = "expected a constant name after ','";
template <> inline constexpr const char* error_message<item_after_comma<multiplier>> = "expected a multiplier after ','";
template <> inline constexpr const char* error_message<name_list> = "expected a comma-separated list of names";
template <> inline constexpr const char* error_message<param_list> = "expected a comma-separated list of parameters, each optionally '= value'";
template <> inline constexpr const char* error_message<const_list> = "expected a comma-separated list of constants, each '= value'";
template <> inline constexpr const char* error_message<measured_equals> = "expected '=' after the measured column's name, as in 'measured a = v''";
template <> inline constexpr const char* error_message<measured_target> = "expected a state's derivative, as in v' or y''";
template <> inline constexpr const char* error_message<item_after_comma<measured_item>> = "expected a measured column after ','";
template <> inline constexpr const char* error_message<measured_list> = "expected a measured column, as in 'measured a = v''";
template <> inline constexpr const char* error_message<candidate_list> = "expected a comma-separated list of parameters";
template <> inline constexpr const char* error_message<item_after_comma<candidate_name>> = "expected a parameter name after ','";
template <> inline constexpr const char* error_message<library_target> = "expected the equation the terms join: a state's derivative (v') or a label";
template <> inline constexpr const char* error_message<library_colon> = "expected ':' after the equation, as in 'library v': y^2, y^3'";
template <> inline constexpr const char* error_message<library_list> = "expected a comma-separated list of terms";
template <> inline constexpr const char* error_message<item_after_comma<library_term>> = "expected a term after ','";
template <> inline constexpr const char* error_message<equals> = "expected '=' of an equation, or a statement keyword (model, state, input, param, const, measured, multipliers, candidate, library)";
template <> inline constexpr const char* error_message<rhs_after_equals> = "expected the right side of the equation after '='";
template <> inline constexpr const char* error_message<multiplier_list> = "expected a comma-separated list of multipliers (monomials in the states)";
template <> inline constexpr const char* error_message<statement_end> = "expected an operator or the end of the line";
template <> inline constexpr const char* error_message<line> = "expected a statement: model, state, input, param, const, measured, multipliers, candidate, library or an equation";
template <> inline constexpr const char* error_message<list_end> = "expected ',' or the end of the multiplier list";
// clang-format on

// Whether `message` belongs to a rule that may start on a later line (after an operator, a comma
// or '('): the parser reports such an error at the end of the previous content instead.
inline bool may_follow_line_break(std::string_view message) {
  for (const char* m :
       {error_message<term_after_operator>, error_message<operand_after_operator>,
        error_message<exponent_after_operator>, error_message<closing_paren>,
        error_message<expression_in_parens>, error_message<item_after_comma<declared_name>>,
        error_message<item_after_comma<param_item>>, error_message<item_after_comma<const_item>>,
        error_message<item_after_comma<measured_item>>, error_message<item_after_comma<multiplier>>,
        error_message<item_after_comma<candidate_name>>,
        error_message<item_after_comma<library_term>>}) {
    if (message == m) return true;
  }
  return false;
}

// The error table for tao::pegtl::must_if: only a failing `must<>` raises; a rule with a
// message that fails elsewhere (inside `sor<>`, `opt<>`) just backtracks.
struct error_messages {
  template <typename Rule>
  static constexpr bool raise_on_failure = false;
  template <typename Rule>
  static constexpr const char* message = error_message<Rule>;
};

}  // namespace momentid::grammar
