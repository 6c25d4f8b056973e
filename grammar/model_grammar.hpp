#pragma once
// The momentid model language as PEGTL rules. grammar/README.md has the same grammar in EBNF
// and an annotated example; grammar/error_messages.hpp says what is reported when a `must<>`
// rule fails. Only src/model/parser.cpp includes this header.

#include <tao/pegtl.hpp>

namespace momentid::grammar {

namespace pegtl = tao::pegtl;
using pegtl::blank;
using pegtl::digit;
using pegtl::eof;
using pegtl::eol;
using pegtl::identifier;
using pegtl::list;
using pegtl::must;
using pegtl::not_at;
using pegtl::not_one;
using pegtl::one;
using pegtl::opt;
using pegtl::plus;
using pegtl::seq;
using pegtl::sor;
using pegtl::star;
using pegtl::string;
using pegtl::until;

// --- Layout ---------------------------------------------------------------------------------

// '#' and the rest of the line
struct comment : seq<one<'#'>, star<not_one<'\n', '\r'>>> {};
// blanks inside a line
struct sp : star<blank> {};
// blanks, comments and line breaks: allowed wherever an expression continues on the next line
struct ws : star<sor<pegtl::space, comment>> {};
// the end of a statement: optional comment, then a line break or the end of the file
struct line_end : seq<sp, opt<comment>, sor<eol, eof>> {};

// --- Words ----------------------------------------------------------------------------------

// a letter or underscore, then letters, digits and underscores
struct name : identifier {};

// A keyword (PEGTL's `keyword`) matches the word itself, not the start of a longer name.
struct kw_model : TAO_PEGTL_KEYWORD("model") {};
// `state` or `states`
struct kw_state : sor<TAO_PEGTL_KEYWORD("states"), TAO_PEGTL_KEYWORD("state")> {};
// `input` or `inputs`
struct kw_input : sor<TAO_PEGTL_KEYWORD("inputs"), TAO_PEGTL_KEYWORD("input")> {};
// `param`, `params`, `parameter` or `parameters`
struct kw_param : sor<TAO_PEGTL_KEYWORD("parameters"), TAO_PEGTL_KEYWORD("parameter"),
                      TAO_PEGTL_KEYWORD("params"), TAO_PEGTL_KEYWORD("param")> {};
// `const`, `consts`, `constant` or `constants`
struct kw_const : sor<TAO_PEGTL_KEYWORD("constants"), TAO_PEGTL_KEYWORD("constant"),
                      TAO_PEGTL_KEYWORD("consts"), TAO_PEGTL_KEYWORD("const")> {};
// `multipliers` or `multiplier`
struct kw_multipliers : sor<TAO_PEGTL_KEYWORD("multipliers"), TAO_PEGTL_KEYWORD("multiplier")> {};
struct kw_dot : TAO_PEGTL_KEYWORD("dot") {};
struct kw_measured : TAO_PEGTL_KEYWORD("measured") {};
// `candidate` or `candidates`
struct kw_candidate : sor<TAO_PEGTL_KEYWORD("candidates"), TAO_PEGTL_KEYWORD("candidate")> {};
struct kw_library : TAO_PEGTL_KEYWORD("library") {};
// `fixed`, after a parameter's value; not reserved, as no name can stand there
struct kw_fixed : TAO_PEGTL_KEYWORD("fixed") {};

// --- Numbers and strings --------------------------------------------------------------------

// digits of an exponent
struct exponent_digits : plus<digit> {};
// e or E, optional sign, digits: the power of ten of a number
struct decimal_exponent : seq<one<'e', 'E'>, opt<one<'+', '-'>>, must<exponent_digits>> {};
// 4, 4., .5, 0.25, 1e-3, 2.5E+2
struct number : seq<sor<seq<plus<digit>, opt<one<'.'>, star<digit>>>, seq<one<'.'>, plus<digit>>>,
                    opt<decimal_exponent>> {};
// a leading minus sign
struct minus_sign : one<'-'> {};
// a leading plus sign
struct plus_sign : one<'+'> {};
// a number with an optional sign, as in a declared value
struct signed_number : seq<opt<sor<minus_sign, plus_sign>>, sp, must<number>> {};
// the characters between double quotes
struct string_body : star<not_one<'"', '\n', '\r'>> {};
struct string_close : one<'"'> {};
// a double-quoted title on one line
struct quoted : seq<one<'"'>, string_body, must<string_close>> {};

// --- Expressions ----------------------------------------------------------------------------

struct expression;
struct close_paren : one<')'> {};
// ')' after an expression, possibly on the next line
struct closing_paren : seq<ws, close_paren> {};
struct open_paren : one<'('> {};
// one or more primes after a name: its time derivative
struct primes : plus<one<'\''>> {};
// a state name inside dot( )
struct dot_argument : name {};
// dot(y): the time derivative of y
struct dot_call : seq<kw_dot, sp, must<open_paren>, sp, must<dot_argument>, sp, must<close_paren>> {
};
// the expressions inside a call's parentheses
struct call_arguments : opt<list<expression, one<','>, pegtl::space>> {};
// name(args): a function call, accepted by the grammar and rejected by the meaning checks
struct call : seq<name, sp, one<'('>, ws, call_arguments, must<closing_paren>> {};
// a word that starts a statement, never a variable
struct reserved : sor<kw_model, kw_state, kw_input, kw_param, kw_const, kw_multipliers, kw_measured,
                      kw_candidate, kw_library> {};
// a name, optionally followed by primes
struct variable : seq<not_at<reserved>, name, opt<primes>> {};
// the expression after '(', possibly on the next line
struct expression_in_parens : seq<ws, expression> {};
// a parenthesised expression
struct parenthesized : seq<one<'('>, must<expression_in_parens>, must<closing_paren>> {};
// the smallest piece of an expression
struct primary : sor<number, dot_call, call, variable, parenthesized> {};
// the operand of a power: optional sign, then a primary
struct exponent_operand : seq<opt<sor<minus_sign, plus_sign>>, sp, primary> {};
// `^` or `**`
struct power_operator : sor<one<'^'>, string<'*', '*'>> {};
// the exponent, possibly on the next line
struct exponent_after_operator : seq<ws, exponent_operand> {};
// a primary raised to a power
struct power : seq<primary, opt<sp, power_operator, must<exponent_after_operator>>> {};
// signs in front of a power
struct unary : seq<star<sor<minus_sign, plus_sign>, sp>, power> {};
// what must follow a binary operator
struct operand : unary {};
// the operand, possibly on the next line
struct operand_after_operator : seq<ws, operand> {};
struct times : seq<one<'*'>, not_at<one<'*'>>> {};
struct divide : one<'/'> {};
// a product or quotient of signed powers; a line break may come before or after the operator
struct product : seq<unary, star<seq<ws, sor<times, divide>, must<operand_after_operator>>>> {};
// what must follow a `+` or `-` between terms
struct term_operand : product {};
// the term, possibly on the next line
struct term_after_operator : seq<ws, term_operand> {};
struct add : one<'+'> {};
struct subtract : one<'-'> {};
// a sum or difference of products; a line break may come before or after the operator
struct sum : seq<product, star<seq<ws, sor<add, subtract>, must<term_after_operator>>>> {};
struct expression : sum {};

// --- Statements -----------------------------------------------------------------------------

// `model NAME "title"`
struct model_name : name {};
struct model_statement : seq<kw_model, sp, must<model_name>, sp, opt<quoted>> {};

// a declared name
struct declared_name : name {};
// `= value` after a declared name
struct declared_value : seq<one<'='>, sp, must<signed_number>> {};
// a declared value that may not be left out
struct required_value : seq<one<'='>, sp, must<signed_number>> {};
struct comma : one<','> {};
// an item after a comma, possibly on the next line
template <typename Item>
struct item_after_comma : seq<ws, Item> {};
// items separated by commas; a line may break after a comma
template <typename Item>
struct comma_list : seq<Item, star<sp, comma, must<item_after_comma<Item>>>> {};
// `state y, v` and `input x`: names only
struct name_list : comma_list<declared_name> {};
// `fixed` after a parameter: its value is known, not estimated
struct fixed_mark : kw_fixed {};
// `param c = 0.5, k, m = 2 fixed` : names with optional nominal values, and known ones
struct param_item : seq<declared_name, sp, opt<declared_value>, sp, opt<fixed_mark>> {};
struct param_list : comma_list<param_item> {};
// `const m = 1`: names with values
struct const_item : seq<declared_name, sp, must<required_value>> {};
struct const_list : comma_list<const_item> {};
struct state_declaration : seq<kw_state, sp, must<name_list>> {};
struct input_declaration : seq<kw_input, sp, must<name_list>> {};
struct param_declaration : seq<kw_param, sp, must<param_list>> {};
struct const_declaration : seq<kw_const, sp, must<const_list>> {};

// `measured a = v'`: the column `a` holds the time derivative of state v (`y''` when y' = v)
struct measured_target : seq<name, primes> {};
struct measured_equals : one<'='> {};
struct measured_item : seq<declared_name, sp, must<measured_equals>, sp, must<measured_target>> {};
struct measured_list : comma_list<measured_item> {};
struct measured_statement : seq<kw_measured, sp, must<measured_list>> {};

// `label:` in front of an equation or inside a multipliers statement
struct label : name {};
struct label_prefix : seq<label, sp, one<':'>, not_at<one<'='>>> {};
// the left side of an equation
struct lhs : expression {};
// the right side of an equation
struct rhs : expression {};
struct equals : one<'='> {};
// `[label:] lhs = rhs`
// the right side, on the same line as '='
struct rhs_after_equals : seq<sp, rhs> {};
struct equation : seq<opt<label_prefix>, sp, lhs, sp, must<equals>, must<rhs_after_equals>> {};

// one multiplier: a monomial in the states
struct multiplier : expression {};
struct multiplier_list : comma_list<multiplier> {};
// `multipliers [label:] m1, m2, ...`
struct multipliers_statement
    : seq<kw_multipliers, sp, opt<label_prefix>, sp, must<multiplier_list>> {};

// `candidate eps, k2`: parameters whose terms term selection may drop
struct candidate_name : name {};
struct candidate_list : comma_list<candidate_name> {};
struct candidate_statement : seq<kw_candidate, sp, must<candidate_list>> {};

// `library v': y^2, y^3, monomials(y, v, 3)`: terms added to the equation of v' (or the one
// labelled), each with a candidate parameter of its own
struct library_target : seq<name, opt<primes>> {};
struct library_colon : one<':'> {};
struct library_term : expression {};
struct library_list : comma_list<library_term> {};
struct library_statement
    : seq<kw_library, sp, must<library_target>, sp, must<library_colon>, sp, must<library_list>> {};

struct statement : sor<model_statement, state_declaration, input_declaration, param_declaration,
                       const_declaration, measured_statement, multipliers_statement,
                       candidate_statement, library_statement, equation> {};
// what may follow a complete statement on its line
struct statement_end : line_end {};
// a line: blank, a comment, or one statement
struct line : seq<sp, sor<line_end, seq<statement, must<statement_end>>>> {};
// a whole model file
struct model_file : until<eof, must<line>> {};

// A multiplier list given on the command line (`--multipliers "y, v^2"`).
// the end of a command-line multiplier list
struct list_end : eof {};
struct multiplier_option : seq<ws, must<multiplier_list>, ws, must<list_end>> {};

}  // namespace momentid::grammar
