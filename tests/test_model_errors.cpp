#include <doctest/doctest.h>

#include <exception>
#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

#include "momentid/model.hpp"
#include "test_support.hpp"

namespace {

using momentid::testing::error_from;

using momentid::LocatedError;
using momentid::Model;
using momentid::ModelError;
using momentid::ParseError;

// The error that parsing the model `text` (named "test.mom") throws.
template <class E>
E error_of(std::string_view text) {
  return error_from<E>([&] { momentid::parse_model(text, "test.mom"); });
}

// The error that parsing `text` as a `--multipliers` list of `model` throws.
template <class E>
E multiplier_error_of(const Model& model, std::string_view text) {
  return error_from<E>([&] { momentid::parse_multiplier_list(model, text, "--multipliers"); });
}

// Checks the message of `e`, where it points, that the location carries the offending source
// line, and that what() is "file:line:col: message".
void check_error(const LocatedError& e, const std::string& message, int line, int column,
                 const std::string& source_line, const std::string& file = "test.mom") {
  CHECK(e.message() == message);
  CHECK(e.location().file == file);
  CHECK(e.location().line == line);
  CHECK(e.location().column == column);
  CHECK(e.location().text == source_line);
  CHECK(std::string(e.what()) ==
        file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + message);
}

// `a - b` expands to zero.
bool same(const GiNaC::ex& a, const GiNaC::ex& b) { return (a - b).expand().is_zero(); }

const Model& oscillator() {
  static const Model model = momentid::parse_model(R"(state y, v
input x
param c, k
y' = v
v' = -c*v - k*y + x
)",
                                                   "oscillator.mom");
  return model;
}

}  // namespace

TEST_SUITE("model errors") {
  // --- Names ----------------------------------------------------------------------------------

  TEST_CASE("an undeclared name is reported with the declared names") {
    const auto e = error_of<ModelError>(R"(state y, v
input x
param c, k
const m = 2
y' = v
m*v' = -c*v - q*y + x
)");
    check_error(e,
                "'q' is not declared (declared: states y, v; inputs x; parameters c, k; "
                "constants m)",
                6, 15, "m*v' = -c*v - q*y + x");
  }

  TEST_CASE("a measured column that is not a state's first or second derivative is refused") {
    constexpr const char* kBody = R"(
param c, k
y' = v
v' = -c*v - k*y + x
)";
    const auto declared = [&](const std::string& statement) {
      return "state y, v\ninput x\n" + statement + kBody;
    };
    check_error(error_of<ModelError>(declared("measured a = w'")),
                "'w' is not declared (declared: states y, v; inputs x; parameters c, k; "
                "measured columns a)",
                3, 14, "measured a = w'");
    check_error(error_of<ModelError>(declared("measured a = x'")),
                "cannot take the time derivative of an input 'x': only states have derivatives", 3,
                14, "measured a = x'");
    check_error(error_of<ModelError>(declared("measured a = y'''")),
                "a measured column holds a state's first or second derivative (v' or y''), "
                "found order 3",
                3, 15, "measured a = y'''");
    check_error(error_of<ModelError>(declared("measured u = y'")),
                "y' = v (equation 1): a column holding y' holds v, which a record gives as the "
                "state's own column (--columns \"v=COLUMN\")",
                3, 14, "measured u = y'");
    check_error(error_of<ModelError>(declared("measured a = v'\nmeasured b = y''")),
                "'a' (line 3) already holds v'", 4, 14, "measured b = y''");
    check_error(error_of<ModelError>(declared("measured a = v''")),
                "v'' needs an equation v' = w with a state w, whose derivative the column then "
                "holds (write 'measured a = w'' with that state)",
                3, 14, "measured a = v''");
    check_error(error_of<ModelError>(declared("measured x = v'")),
                "'x' is already declared as an input at 2:7", 3, 10, "measured x = v'");
    check_error(error_of<ModelError>("state y, v\ninput x\nmeasured a = v'\nparam c, k\n"
                                     "y' = v\nv' = -c*v - k*y + x + a\n"),
                "'a' is a measured column, which equations do not name: write the derivative "
                "it holds, v'",
                6, 23, "v' = -c*v - k*y + x + a");
    check_error(error_of<ParseError>(declared("measured a v'")),
                "expected '=' after the measured column's name, as in 'measured a = v''", 3, 12,
                "measured a v'");
    check_error(error_of<ParseError>(declared("measured a = v")),
                "expected a state's derivative, as in v' or y''", 3, 15, "measured a = v");
    check_error(error_of<ModelError>(declared("measured model = v'")),
                "'model' is a reserved word and cannot be declared", 3, 10, "measured model = v'");
  }

  TEST_CASE("a fixed parameter without a value is reported at 'fixed'") {
    const auto e = error_of<ModelError>("state y\nparam c, k fixed\ny' = -c*y - k*y^3\n");
    check_error(e, "a fixed parameter needs its value: write 'k = VALUE fixed'", 2, 12,
                "param c, k fixed");
  }

  TEST_CASE("a name declared twice as the same kind is reported with the first declaration") {
    const auto e = error_of<ModelError>(R"(state y, v
param k
state y
y' = v
v' = -k*y
)");
    check_error(e, "'y' is already declared as a state at 1:7", 3, 7, "state y");
  }

  TEST_CASE("a name declared as two kinds is reported with the kind it was declared first") {
    const auto state_then_param = error_of<ModelError>(R"(state y, v
param k, y
y' = v
v' = -k*y
)");
    check_error(state_then_param, "'y' is already declared as a state at 1:7", 2, 10, "param k, y");

    const auto param_then_const = error_of<ModelError>(R"(state y, v
param k
const m = 1, k = 2
y' = v
v' = -k*y
)");
    check_error(param_then_const, "'k' is already declared as a parameter at 2:7", 3, 14,
                "const m = 1, k = 2");
  }

  // --- Derivatives ----------------------------------------------------------------------------

  TEST_CASE("the derivative of an input is rejected in both notations") {
    const auto primed = error_of<ModelError>(R"(state y, v
input x
param k
y' = v
v' = -k*y + x'
)");
    check_error(primed,
                "cannot take the time derivative of an input 'x': only states have derivatives", 5,
                13, "v' = -k*y + x'");

    const auto dotted = error_of<ModelError>(R"(state y, v
input x
param k
y' = v
v' = -k*y + dot(x)
)");
    check_error(dotted,
                "cannot take the time derivative of an input 'x': only states have derivatives", 5,
                17, "v' = -k*y + dot(x)");
  }

  TEST_CASE("the derivative of a parameter is rejected in both notations") {
    const auto primed = error_of<ModelError>(R"(state y, v
param k
y' = v
v' = -k*y - k'*y
)");
    check_error(primed,
                "cannot take the time derivative of a parameter 'k': only states have derivatives",
                4, 13, "v' = -k*y - k'*y");

    const auto dotted = error_of<ModelError>(R"(state y, v
param k
y' = v
v' = -k*y - dot(k)*y
)");
    check_error(dotted,
                "cannot take the time derivative of a parameter 'k': only states have derivatives",
                4, 17, "v' = -k*y - dot(k)*y");
  }

  TEST_CASE("the derivative of a constant is rejected in both notations") {
    const auto primed = error_of<ModelError>(R"(state y, v
param k
const m = 2
y' = v
m'*v + m*v' = -k*y
)");
    check_error(primed,
                "cannot take the time derivative of a constant 'm': only states have derivatives",
                5, 1, "m'*v + m*v' = -k*y");

    const auto dotted = error_of<ModelError>(R"(state y, v
param k
const m = 2
y' = v
dot(m)*v + m*v' = -k*y
)");
    check_error(dotted,
                "cannot take the time derivative of a constant 'm': only states have derivatives",
                5, 5, "dot(m)*v + m*v' = -k*y");
  }

  TEST_CASE("a second derivative asks for the first-order form") {
    const auto e = error_of<ModelError>(R"(state y
param c, k
y'' = -c*y' - k*y
)");
    check_error(e,
                "derivatives of order 2 are not supported: write the model in first-order form, "
                "with a state for 'y''",
                3, 2, "y'' = -c*y' - k*y");
  }

  // --- Powers and quotients -------------------------------------------------------------------

  TEST_CASE("a non-integer exponent is rejected") {
    const auto e = error_of<ModelError>(R"(state y
param k
y' = -k*y^2.5
)");
    check_error(e, "the exponent must be a non-negative integer, found '2.5'", 3, 11,
                "y' = -k*y^2.5");
  }

  TEST_CASE("a negative exponent is rejected") {
    const auto e = error_of<ModelError>(R"(state y
param k
y' = -k*y^-1
)");
    check_error(e, "the exponent must be a non-negative integer, found '-1'", 3, 11,
                "y' = -k*y^-1");
  }

  TEST_CASE("a symbolic exponent is rejected") {
    const auto e = error_of<ModelError>(R"(state y
param k
y' = -y^k
)");
    check_error(e, "the exponent must be a non-negative integer, found 'k'", 3, 9, "y' = -y^k");
  }

  TEST_CASE("an exponent above 64 is rejected") {
    const auto e = error_of<ModelError>(R"(state y
param k
y' = -k*y^65
)");
    check_error(e, "the exponent 65 is too large (at most 64)", 3, 11, "y' = -k*y^65");
  }

  TEST_CASE("division by a parameter or a state is rejected") {
    const auto by_parameter = error_of<ModelError>(R"(state y
param k
y' = -y/k
)");
    check_error(by_parameter, "can only divide by a number, found 'k'", 3, 9, "y' = -y/k");

    const auto by_state = error_of<ModelError>(R"(state y
param k
y' = -k/y
)");
    check_error(by_state, "can only divide by a number, found 'y'", 3, 9, "y' = -k/y");
  }

  TEST_CASE("division by zero is rejected, also by an expression that is zero") {
    const auto literal = error_of<ModelError>(R"(state y
param k
y' = -k*y/0
)");
    check_error(literal, "division by zero", 3, 11, "y' = -k*y/0");

    const auto computed = error_of<ModelError>(R"(state y
param k
y' = -k*y/(2 - 2)
)");
    check_error(computed, "division by zero", 3, 11, "y' = -k*y/(2 - 2)");
  }

  // --- Calls ----------------------------------------------------------------------------------

  TEST_CASE("a function call is rejected") {
    const auto e = error_of<ModelError>(R"(state y
param k
y' = -k*sin(y)
)");
    check_error(e,
                "function 'sin' is not allowed: equations are polynomials, with abs(...) and "
                "sign(...) of a polynomial in the states and inputs (and dot(...))",
                3, 9, "y' = -k*sin(y)");
  }

  TEST_CASE("a declared name used as a function suggests a product") {
    const auto e = error_of<ModelError>(R"(state y
param k
y' = -k(y + 1)
)");
    check_error(e, "'k' is a parameter, not a function: write 'k*(...)' for a product", 3, 7,
                "y' = -k(y + 1)");
  }

  // --- Terms ----------------------------------------------------------------------------------

  TEST_CASE("a term with a squared parameter is not affine in the parameters") {
    const auto e = error_of<ModelError>(R"(state y, v
param c, k
y' = v
v' = -c*v - k^2*y
)");
    check_error(e,
                "term 'k^2*y' is not affine in the parameters: a term may contain at most one "
                "parameter factor",
                4, 13, "v' = -c*v - k^2*y");
  }

  TEST_CASE("a term with a product of two parameters is not affine in the parameters") {
    const auto e = error_of<ModelError>(R"(state y, v
param c, k
y' = v
v' = -c*v - c*k*y
)");
    check_error(e,
                "term 'c*k*y' is not affine in the parameters: a term may contain at most one "
                "parameter factor",
                4, 13, "v' = -c*v - c*k*y");
  }

  TEST_CASE("a nested product of parameters is reported as the expanded term") {
    const auto e = error_of<ModelError>(R"(state y, v
param c, k
y' = v
v' = -c*(k*y + 1)
)");
    check_error(e,
                "term '-c*k*y' is not affine in the parameters: a term may contain at most one "
                "parameter factor",
                4, 6, "v' = -c*(k*y + 1)");
  }

  TEST_CASE("a term with two derivative factors is rejected") {
    const auto e = error_of<ModelError>(R"(state y, v
param c, k
y' = v
v' + y'*v' = -c*v - k*y
)");
    check_error(e, "term 'y'*v'' has 2 derivative factors: a term may contain at most one", 4, 6,
                "v' + y'*v' = -c*v - k*y");
  }

  // --- The model as a whole -------------------------------------------------------------------

  TEST_CASE("a state whose derivative no equation contains is reported at its declaration") {
    const auto e = error_of<ModelError>(R"(state y, v
param k
y' = v
v = -k*y
)");
    check_error(e, "no equation determines the derivative of state 'v' (no equation contains v')",
                1, 10, "state y, v");
  }

  TEST_CASE("two states competing for one equation are reported at the one left without") {
    const auto e = error_of<ModelError>(R"(state y, v
param k
y' + v' = -k*y
v = y
)");
    check_error(e,
                "no equation is left to determine the derivative of state 'v': the equations "
                "containing it are needed for other states",
                1, 10, "state y, v");
  }

  TEST_CASE("a model without states is rejected at its first line") {
    const auto empty = error_of<ModelError>("");
    check_error(empty, "the model declares no states (expected a 'state' statement)", 1, 1, "");

    const auto comments_only = error_of<ModelError>(R"(# nothing yet
model empty "Nothing declared"
)");
    check_error(comments_only, "the model declares no states (expected a 'state' statement)", 1, 1,
                "# nothing yet");
  }

  TEST_CASE("a model with states but no equations is rejected at its first line") {
    const auto e = error_of<ModelError>(R"(model quiet
state y, v
param k
)");
    check_error(e, "the model has no equations", 1, 1, "model quiet");
  }

  TEST_CASE("a parameter that appears in no equation is reported at its declaration") {
    const auto e = error_of<ModelError>(R"(state y
param c, k
y' = -k*y
)");
    check_error(e, "parameter 'c' appears in no equation", 2, 7, "param c, k");
  }

  TEST_CASE("an equation that reduces to 0 = 0 is rejected") {
    const auto e = error_of<ModelError>(R"(state y
param k
y' = -k*y
k*y = y*k
)");
    check_error(e, "the equation reduces to 0 = 0", 4, 1, "k*y = y*k");
  }

  TEST_CASE("a label used twice is reported with the line of its first use") {
    const auto e = error_of<ModelError>(R"(state y, v
param k
a: y' = v
a: v' = -k*y
)");
    check_error(e, "label 'a' is already used on line 3", 4, 1, "a: v' = -k*y");
  }

  TEST_CASE("a second model statement is reported with the line of the first") {
    const auto e = error_of<ModelError>(R"(model first
state y
param k
model second
y' = -k*y
)");
    check_error(e, "a second 'model' statement (the first is on line 1)", 4, 1, "model second");
  }

  // --- Multipliers statements -----------------------------------------------------------------

  TEST_CASE("a multipliers statement for an unknown label lists the labels") {
    const auto e = error_of<ModelError>(R"(state y, v
param k
position: y' = v
motion: v' = -k*y
multipliers force: y, v
)");
    check_error(e, "no equation is labelled 'force' (labels: position, motion)", 5, 13,
                "multipliers force: y, v");
  }

  TEST_CASE("a multipliers statement for a label in a model without labels says so") {
    const auto e = error_of<ModelError>(R"(state y, v
param k
y' = v
v' = -k*y
multipliers motion: y
)");
    check_error(e, "no equation is labelled 'motion' (no equation has a label)", 5, 13,
                "multipliers motion: y");
  }

  TEST_CASE("a multiplier that is a sum is not a monomial") {
    const auto e = error_of<ModelError>(R"(state y, v
param k
y' = v
v' = -k*y
multipliers y + v
)");
    check_error(e,
                "a multiplier must be a monomial in the states, such as y or y^2*v, found 'y + v'",
                5, 13, "multipliers y + v");
  }

  TEST_CASE("a multiplier with an input is rejected naming the input") {
    const auto e = error_of<ModelError>(R"(state y, v
input x
param k
y' = v
v' = -k*y + x
multipliers y, v*x
)");
    check_error(e, "multiplier 'v*x' contains input 'x': multipliers are monomials in the states",
                6, 16, "multipliers y, v*x");
  }

  TEST_CASE("a multiplier with a coefficient is not a monomial") {
    const auto e = error_of<ModelError>(R"(state y, v
param k
y' = v
v' = -k*y
multipliers y, 2*y
)");
    check_error(e, "a multiplier must be a monomial in the states, such as y or y^2*v, found '2*y'",
                5, 16, "multipliers y, 2*y");
  }

  // --- Grammar --------------------------------------------------------------------------------

  TEST_CASE("an equation without '=' names what was expected") {
    const auto e = error_of<ParseError>(R"(state y, v
param k
y' v
v' = -k*y
)");
    check_error(e,
                "expected '=' of an equation, or a statement keyword (model, state, input, param, "
                "const, measured, multipliers, candidate, library)",
                3, 4, "y' v");
  }

  TEST_CASE("an equation with nothing after '=' at the end of the file is reported after '='") {
    // The file ends without a line break, right after '='.
    const auto e = error_of<ParseError>("state y\nparam k\ny' =");
    check_error(e, "expected the right side of the equation after '='", 3, 5, "y' =");
  }

  TEST_CASE("an operator at the end of the file is reported where its operand is missing") {
    // The file ends without a line break, right after the operator.
    const auto e = error_of<ParseError>("state y\nparam c, k\ny' = -k*y + c*");
    check_error(e, "expected an operand after the operator", 3, 15, "y' = -k*y + c*");

    const auto sum = error_of<ParseError>("state y\nparam k\ny' = -k*y +");
    check_error(sum, "expected a term after the operator", 3, 12, "y' = -k*y +");
  }

  TEST_CASE("a parenthesis still open at the end of the file is reported there") {
    // The file ends without a line break, inside the parentheses.
    const auto e = error_of<ParseError>("state y\nparam k\ny' = -k*(y + 1");
    check_error(e, "expected ')'", 3, 15, "y' = -k*(y + 1");
  }

  TEST_CASE("a title string not closed on its line is reported at the line end") {
    const auto e = error_of<ParseError>(R"(model duffing "Forced Duffing
state y
param k
y' = -k*y
)");
    check_error(e, "expected '\"' to close the title on the same line", 1, 30,
                "model duffing \"Forced Duffing");
  }

  TEST_CASE("a number with an exponent mark but no digits is rejected") {
    const auto in_value = error_of<ParseError>(R"(state y
param k = 1e
y' = -k*y
)");
    check_error(in_value, "expected digits after the exponent mark of a number", 2, 13,
                "param k = 1e");

    const auto in_equation = error_of<ParseError>(R"(state y
param k
y' = -1e*k*y
)");
    check_error(in_equation, "expected digits after the exponent mark of a number", 3, 9,
                "y' = -1e*k*y");
  }

  TEST_CASE("a constant without a value is rejected") {
    const auto e = error_of<ParseError>(R"(state y
param k
const m, g = 9.81
m*y' = -k*y
)");
    check_error(e, "expected '= value': a constant needs a value", 3, 8, "const m, g = 9.81");
  }

  TEST_CASE("a stray token after a complete statement is rejected") {
    const auto e = error_of<ParseError>(R"(state y, v
param k
y' = v v
v' = -k*y
)");
    check_error(e, "expected an operator or the end of the line", 3, 8, "y' = v v");
  }

  TEST_CASE("dot takes a single name") {
    const auto e = error_of<ParseError>(R"(state y, v
param k
dot(y+1) = v
v' = -k*y
)");
    check_error(e, "expected ')'", 3, 6, "dot(y+1) = v");
  }

  TEST_CASE("a line that starts no statement is rejected") {
    const auto e = error_of<ParseError>(R"(state y
param k
$ y' = -k*y
)");
    check_error(e,
                "expected a statement: model, state, input, param, const, measured, multipliers, "
                "candidate, library or an equation",
                3, 1, "$ y' = -k*y");
  }

  // --- Command-line multiplier lists ----------------------------------------------------------

  TEST_CASE("a command-line multiplier with an undeclared name lists the declared names") {
    const auto e = multiplier_error_of<ModelError>(oscillator(), "y, q^2");
    check_error(e, "'q' is not declared (declared: states y, v; inputs x; parameters c, k)", 1, 4,
                "y, q^2", "--multipliers");
  }

  TEST_CASE("a command-line multiplier with an input is rejected naming the input") {
    const auto e = multiplier_error_of<ModelError>(oscillator(), "y, x*v");
    check_error(e, "multiplier 'x*v' contains input 'x': multipliers are monomials in the states",
                1, 4, "y, x*v", "--multipliers");
  }

  TEST_CASE("trailing garbage after a command-line multiplier list is rejected") {
    const auto e = multiplier_error_of<ParseError>(oscillator(), "y, v )");
    check_error(e, "expected ',' or the end of the multiplier list", 1, 6, "y, v )",
                "--multipliers");
  }

  // --- What the language accepts --------------------------------------------------------------

  TEST_CASE("plural keywords and '**' for powers are accepted") {
    const Model model = momentid::parse_model(R"(model duffing "Duffing"
states y, v
inputs x
params c, k
parameters eps
constants m = 2
y' = v
m*v' = -c*v - k*y - eps*y**3 + x
)",
                                              "test.mom");
    CHECK(model.states().size() == 2);
    CHECK(model.inputs().size() == 1);
    CHECK(model.parameters().size() == 3);
    REQUIRE(model.constants().size() == 1);
    CHECK(*model.constants()[0].value == 2);
    REQUIRE(model.equations().size() == 2);
    const GiNaC::ex y = model.state_symbol(0), v = model.state_symbol(1);
    const GiNaC::ex c = model.parameter_symbol(0), k = model.parameter_symbol(1),
                    eps = model.parameter_symbol(2);
    CHECK(same(model.equations()[1].lhs, 2 * model.derivative_symbol(1)));
    CHECK(same(model.equations()[1].rhs,
               -c * v - k * y - eps * GiNaC::pow(y, 3) + model.input_symbol(0)));
  }

  TEST_CASE("an expression continues on the next line after or before an operator") {
    const Model model = momentid::parse_model(R"(state y, v
param c, k
y' = v
v' = -c*v -
     k*y
v' = -c*v
     - k*y
)",
                                              "test.mom");
    REQUIRE(model.equations().size() == 3);
    const GiNaC::ex y = model.state_symbol(0), v = model.state_symbol(1);
    const GiNaC::ex c = model.parameter_symbol(0), k = model.parameter_symbol(1);
    CHECK(same(model.equations()[1].rhs, -c * v - k * y));
    CHECK(same(model.equations()[2].rhs, -c * v - k * y));
    CHECK(model.equations()[2].where.line == 6);
  }

  TEST_CASE("dot(y) is the derivative of y") {
    const Model model = momentid::parse_model(R"(state y, v
param k
dot(y) = v
dot( v ) = -k*y
)",
                                              "test.mom");
    REQUIRE(model.equations().size() == 2);
    CHECK(same(model.equations()[0].lhs, model.derivative_symbol(0)));
    CHECK(same(model.equations()[1].lhs, model.derivative_symbol(1)));
  }

  TEST_CASE("comments and blank lines are ignored, also inside a continued expression") {
    const Model model = momentid::parse_model(R"(# a comment line

state y, v   # a comment after a statement
param c, k
y' = v
v' = -c*v    # damping

     - k*y   # stiffness
)",
                                              "test.mom");
    REQUIRE(model.equations().size() == 2);
    CHECK(same(model.equations()[1].rhs, -model.parameter_symbol(0) * model.state_symbol(1) -
                                             model.parameter_symbol(1) * model.state_symbol(0)));
  }

  TEST_CASE("statements may come in any order") {
    const Model model = momentid::parse_model(R"(y' = v
v' = -k*y + x
param k
input x
state y, v
)",
                                              "test.mom");
    CHECK(model.channel_names() == std::vector<std::string>{"y", "v", "x"});
    REQUIRE(model.equations().size() == 2);
    CHECK(same(model.equations()[1].rhs,
               -model.parameter_symbol(0) * model.state_symbol(0) + model.input_symbol(0)));
  }

  TEST_CASE("declared values are read exactly") {
    const Model model = momentid::parse_model(R"(state y
param k = 0.1
const a = .5, b = 1e-3, c = 2.5E+2, d = 4.
y' = -a*b*c*d*k*y
)",
                                              "test.mom");
    REQUIRE(model.parameters().size() == 1);
    CHECK(*model.parameters()[0].value == GiNaC::numeric(1, 10));
    REQUIRE(model.constants().size() == 4);
    CHECK(*model.constants()[0].value == GiNaC::numeric(1, 2));
    CHECK(*model.constants()[1].value == GiNaC::numeric(1, 1000));
    CHECK(*model.constants()[2].value == 250);
    CHECK(*model.constants()[3].value == 4);
    // a*b*c*d = 1/2
    CHECK(same(model.equations()[0].rhs,
               GiNaC::numeric(-1, 2) * model.parameter_symbol(0) * model.state_symbol(0)));
  }

  TEST_CASE("a command-line multiplier list gives monomials in the states") {
    const std::vector<momentid::Monomial> monomials =
        momentid::parse_multiplier_list(oscillator(), " y , v^2,y*v ", "--multipliers");
    CHECK(monomials == std::vector<momentid::Monomial>{{1, 0}, {0, 2}, {1, 1}});
  }

  // --- Regressions: continuation lines, lists, values -----------------------------------------

  TEST_CASE("an operator at the end of a line with nothing after it is reported on its line") {
    const auto e = error_of<ParseError>("state y\nparam c\ny' = -c*y +\n\nmultipliers y\n");
    check_error(e, "expected a term after the operator", 3, 12, "y' = -c*y +");
    const auto f = error_of<ParseError>("state y\nparam c\ny' = -c*y *\n");
    check_error(f, "expected an operand after the operator", 3, 12, "y' = -c*y *");
  }

  TEST_CASE("an unclosed parenthesis is reported where the expression ends") {
    const auto e = error_of<ParseError>("state y\nparam c\ny' = -c*(y + 1\nmultipliers y\n");
    check_error(e, "expected ')'", 3, 15, "y' = -c*(y + 1");
  }

  TEST_CASE("the right side of an equation must start on the line of '='") {
    const auto e = error_of<ParseError>("state y\nparam c\ny' =\n  -c*y\n");
    check_error(e, "expected the right side of the equation after '='", 3, 5, "y' =");
  }

  TEST_CASE("a list that ends with a comma asks for the next item") {
    check_error(error_of<ParseError>("state y,\n"), "expected a name after ','", 1, 9, "state y,");
    check_error(error_of<ParseError>("state y\nparam c,\n"), "expected a parameter name after ','",
                2, 9, "param c,");
    check_error(error_of<ParseError>("state y\nconst m = 1,\n"),
                "expected a constant name after ','", 2, 13, "const m = 1,");
    check_error(multiplier_error_of<ParseError>(oscillator(), "y,"),
                "expected a multiplier after ','", 1, 3, "y,", "--multipliers");
  }

  TEST_CASE("a list may continue on the next line after a comma") {
    const Model model = momentid::parse_model(
        "state y,\n      v\ninput x\nparam c,\n k\n"
        "y' = v\nv' = -c*v - k*y + x\n",
        "test.mom");
    CHECK(model.states().size() == 2);
    CHECK(model.parameters().size() == 2);
  }

  TEST_CASE("declared values keep their sign") {
    const Model model = momentid::parse_model(
        "state y\nparam k = -0.5\nconst a = -2, b = +3\ny' = -a*k*y + b*y\n", "test.mom");
    CHECK(*model.parameters()[0].value == GiNaC::numeric(-1, 2));
    CHECK(*model.constants()[0].value == -2);
    CHECK(*model.constants()[1].value == 3);
    const GiNaC::ex y = model.state_symbol(0), k = model.parameter_symbol(0);
    CHECK(same(model.equations()[0].rhs, 2 * k * y + 3 * y));
  }

  TEST_CASE("a number beyond the accepted range of powers of ten is an error") {
    const auto e = error_of<ModelError>("state y\nparam c\nconst a = 1e200000\ny' = -c*y + a\n");
    check_error(e,
                "the number '1e200000' is out of range (powers of ten from -1000 to 1000 and at "
                "most 1000 digits are accepted)",
                3, 11, "const a = 1e200000");
    const Model zero =
        momentid::parse_model("state y\nparam c\ny' = -c*y + 0e99999*y\n", "test.mom");
    CHECK(zero.equations()[0].terms.size() == 2);
  }

  TEST_CASE("0^0 is reported at the power") {
    const auto e = error_of<ModelError>("state y\nparam k\ny' = k*y + (y - y)^0\n");
    check_error(e, "0^0 is undefined", 3, 12, "y' = k*y + (y - y)^0");
  }

  TEST_CASE("keywords cannot be declared") {
    const auto e = error_of<ModelError>("state y, dot\n");
    check_error(e, "'dot' is a reserved word and cannot be declared", 1, 10, "state y, dot");
  }

  TEST_CASE("equations that cannot be solved for the derivatives are rejected") {
    const auto e = error_of<ModelError>(
        "state y, v\ninput x\nparam c, k\ny' + v' = v\n2*y' + 2*v' = -c*v - k*y + x\n");
    check_error(e,
                "the equations cannot be solved for the derivatives of the states (y, v): their "
                "coefficients are linearly dependent",
                4, 1, "y' + v' = v");
  }

  // --- Limits -----------------------------------------------------------------------------------

  TEST_CASE("parentheses nested too deep are an error, not a stack overflow") {
    const std::string text = "state y\ninput x\nparam a\ny' = -a*" + std::string(5000, '(') + "y" +
                             std::string(5000, ')') + " + x\n";
    const auto e = error_of<ParseError>(text);
    CHECK(e.message() == "parentheses are nested more than 200 deep");
    CHECK(e.location().line == 4);
    CHECK(e.location().column == 209);
  }

  TEST_CASE("a term or multiplier of too high a degree is an error") {
    const auto e = error_of<ModelError>("state y\nparam a\ny' = -a*(y^64)^64\n");
    check_error(e, "this term has degree 4096, above the highest allowed (64)", 3, 9,
                "y' = -a*(y^64)^64");
    std::string product = "y";
    for (int i = 0; i < 99; ++i) product += "*y";
    const auto f =
        error_of<ModelError>("state y\nparam a\ny' = -a*y\nmultipliers " + product + "\n");
    CHECK(f.message() == "this term has degree 65, above the highest allowed (64)");
    const auto g = multiplier_error_of<ModelError>(oscillator(), "(((y^64)^64)^64)^64");
    CHECK(g.message() == "this term has degree 4096, above the highest allowed (64)");
  }

  TEST_CASE("a power of a number that would be huge is an error") {
    const auto e = error_of<ModelError>(
        "state y\ninput x\nparam a\ny' = -a*y + x + "
        "0*((1e1000)^64)^64*y\n");
    check_error(e, "the number is too large (about 1e64000; at most 1e2000)", 4, 20,
                "y' = -a*y + x + 0*((1e1000)^64)^64*y");
  }

  TEST_CASE("a byte order mark before the model is ignored") {
    const Model model =
        momentid::parse_model("\xEF\xBB\xBFstate y\ninput x\nparam a\ny' = -a*y + x\n", "b.mom");
    CHECK(model.states().size() == 1);
  }

  TEST_CASE("a directory given as the model file is reported as such") {
    const auto e = error_from<momentid::Error>(
        [] { momentid::parse_model_file(std::string(MOMENTID_SOURCE_DIR) + "/models"); });
    CHECK(std::string(e.what()) == std::string(MOMENTID_SOURCE_DIR) +
                                       "/models: cannot read the model file: it is a directory");
  }

  TEST_CASE("a model named after its file keeps only safe characters") {
    const Model model = momentid::parse_model("state y\ninput x\nparam a\ny' = -a*y + x\n",
                                              "dir/we\xffird name.mom");
    CHECK(model.name() == "we_ird_name");
  }

  TEST_CASE("a long source line is shown as a window around the caret") {
    const std::string text = "state y\ninput x\nparam a\ny' = -a*y + x" + std::string(200, ' ') +
                             "+ q" + std::string(200, ' ') + "\n";
    const auto e = error_of<ModelError>(text);
    const std::string shown = momentid::render_with_caret(e);
    const std::string line = text.substr(24, text.size() - 25);  // line 4, without its '\n'
    const std::string window = "..." + line.substr(215 - 70, 70 + 50) + "...";
    CHECK(shown ==
          "test.mom:4:216: 'q' is not declared (declared: states y; inputs x; "
          "parameters a)\n 4 | " +
              window + "\n   | " + std::string(73, ' ') + "^");
  }

  TEST_CASE("a character that reorders text is shown as '?' in the source line") {
    // U+202E (right-to-left override) after y: the terminal would show the line reversed.
    const auto e = error_of<ParseError>("state y\nparam a\ny\xE2\x80\xAE = -a*y\n");
    CHECK(momentid::render_with_caret(e) ==
          "test.mom:3:2: expected '=' of an equation, or a statement keyword (model, state, "
          "input, param, const, measured, multipliers, candidate, library)\n 3 | y? = -a*y\n   "
          "|  ^");
    CHECK(momentid::printable("a\xE2\x81\xA6"
                              "b\xD8\x9C"
                              "c \xC3\xA9") == "a?b?c \xC3\xA9");
  }
}
