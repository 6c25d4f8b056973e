// The `library` and `candidate` statements: the terms and parameters they add, and every message
// they give.

#include <doctest/doctest.h>

#include <string>
#include <string_view>
#include <vector>

#include "momentid/lagged.hpp"
#include "momentid/model.hpp"
#include "test_support.hpp"

namespace {

using momentid::LocatedError;
using momentid::Model;
using momentid::ModelError;
using momentid::ParseError;
using momentid::testing::error_from;

constexpr std::string_view kHead = R"(state y, v
input x
param c
y' = v
motion: v' = -c*v + x
)";

Model parsed(std::string_view statements) {
  return momentid::parse_model(std::string(kHead) + std::string(statements), "test.mom");
}

template <class E>
E error_of(std::string_view statements) {
  return error_from<E>([&] { parsed(statements); });
}

void check_error(const LocatedError& e, const std::string& message, int column, int line = 6) {
  CHECK(e.message() == message);
  CHECK(e.location().line == line);
  CHECK(e.location().column == column);
}

std::vector<std::string> names(const Model& m, bool candidates) {
  std::vector<std::string> out;
  for (const auto& p : m.parameters()) {
    if (p.candidate == candidates) out.push_back(p.name);
  }
  return out;
}

// The monomials of the parameter named `name` in equation 2, as its terms hold them.
std::string terms_of(const Model& m, const std::string& name) {
  std::string out;
  for (const auto& t : m.equations()[1].terms) {
    if (t.parameter == m.parameter_index(name)) {
      if (!out.empty()) out += ",";
      out += momentid::format_monomial(m, t.monomial);
    }
  }
  return out;
}

}  // namespace

TEST_SUITE("library") {
  TEST_CASE("a library adds a candidate parameter per term, named after the equation and term") {
    const Model m = parsed("library v': y, y^2*x, abs(v)*v\n");
    CHECK(names(m, false) == std::vector<std::string>{"c"});
    CHECK(names(m, true) == std::vector<std::string>{"v_y", "v_y2_x", "v_v_absv"});
    CHECK(terms_of(m, "v_y2_x") == "y^2*x");
    CHECK(terms_of(m, "v_v_absv") == "v*abs(v)");
    // Each term joins the right side: v' = -c*v + x + v_y*y + ..., so lhs - rhs holds -v_y*y.
    for (const auto& t : m.equations()[1].terms) {
      if (t.parameter == m.parameter_index("v_y")) CHECK(t.coefficient == -1);
    }
    CHECK(m.equations()[0].terms.size() == 2);  // y' = v untouched
  }

  TEST_CASE("monomials() makes every monomial up to the degree, skipping terms already there") {
    const Model m = parsed("library motion: monomials(y, v, 2)\n");
    // y, v (carried by c: skipped), y^2, y*v, v^2
    CHECK(names(m, true) ==
          std::vector<std::string>{"motion_y", "motion_y2", "motion_y_v", "motion_v2"});
    const Model powers = parsed("library v': monomials(y, 3), x\n");
    CHECK(names(powers, true) == std::vector<std::string>{"v_y", "v_y2", "v_y3", "v_x"});
  }

  TEST_CASE("candidate marks declared parameters") {
    const Model m = parsed("candidate c\n");
    CHECK(names(m, true) == std::vector<std::string>{"c"});
    CHECK(names(parsed("library v': y\ncandidates c, v_y\n"), true) ==
          std::vector<std::string>{"c", "v_y"});
  }

  TEST_CASE("the constant 1 is a term whose parameter is the constant") {
    const Model m = parsed("library v': 1, y\n");
    CHECK(names(m, true) == std::vector<std::string>{"v_const", "v_y"});
    CHECK(terms_of(m, "v_const") == "1");
  }

  TEST_CASE("a name ending in a digit keeps its exponent apart") {
    const Model m = momentid::parse_model(
        "state y1, v1\ny1' = v1\nv1' = 0\nlibrary v1': y1^2, y1*v1\n", "test.mom");
    CHECK(names(m, true) == std::vector<std::string>{"v1_y1p2", "v1_y1_v1"});
  }

  TEST_CASE("messages") {
    check_error(error_of<ModelError>("library v': y + v\n"),
                "a library term is one product of states, inputs, abs(...) and sign(...), found 2 "
                "terms in 'y + v' (write a sum by hand with a 'candidate' parameter)",
                13);
    check_error(error_of<ModelError>("library v': c*y\n"),
                "a library term has no parameter, found 'c*y': the library gives each term a "
                "parameter of its own",
                13);
    check_error(error_of<ModelError>("library v': 3\n"),
                "a constant library term is written 1 (its parameter is the constant), found '3'",
                13);
    check_error(error_of<ModelError>("library v': y, 1, 1\n"),
                "'1' is already a term of equation motion, with parameter v_const", 19);
    check_error(error_of<ModelError>("library v': y'\n"),
                "a library term cannot hold a derivative, found 'y''", 13);
    check_error(error_of<ModelError>("library v': v\n"),
                "'v' is already a term of equation motion, with parameter c: write 'candidate c' "
                "instead",
                13);
    check_error(error_of<ModelError>("library v': y, y\n"),
                "'y' is already a term of equation motion, with parameter v_y", 16);
    check_error(error_of<ModelError>("library w': y\n"),
                "'w' is not declared (declared: states y, v; inputs x; parameters c)", 9);
    check_error(error_of<ModelError>("library x': y\n"),
                "cannot take the time derivative of an input 'x': only states have derivatives", 9);
    check_error(error_of<ModelError>("library v'': y\n"),
                "expected a state's first derivative, as in v', found 'v'''", 9);
    check_error(error_of<ModelError>("library q: y\n"),
                "no equation is labelled 'q': name the equation by a label or by a state's "
                "derivative, as in 'library v': ...'",
                9);
    check_error(error_of<ModelError>("library v: y\n"),
                "no equation is labelled 'v': write v' for the equation of its derivative", 9);
    check_error(error_of<ModelError>("library v': monomials(y, 0)\n"),
                "expected the highest degree, a whole number from 1 to 9, as the last argument of "
                "monomials(NAME, ..., DEGREE): the monomials of degree 1 to DEGREE in the states "
                "and inputs named, found '0'",
                26);
    check_error(error_of<ModelError>("library v': monomials(c, 2)\n"),
                "expected a state or an input in monomials(NAME, ..., DEGREE): the monomials of "
                "degree 1 to DEGREE in the states and inputs named, found 'c'",
                23);
    check_error(error_of<ModelError>("library v': monomials(y, y, 2)\n"),
                "'y' is named twice in monomials(...)", 26);
    check_error(error_of<ModelError>("library v': monomials(y)\n"),
                "expected monomials(NAME, ..., DEGREE): the monomials of degree 1 to DEGREE in "
                "the states and inputs named",
                13);
    check_error(error_of<ModelError>("library v': monomials(y, v, x, 9)\n"),
                "monomials(...) would make 219 terms, more than 200: name fewer variables or a "
                "lower degree",
                13);
    check_error(error_of<ModelError>("param v_y\nlibrary v': y\n"),
                "the library names the parameter of 'y' v_y, which is declared as a parameter on "
                "line 6: rename that declaration",
                13, 7);
    check_error(error_of<ModelError>("candidate q\n"),
                "'q' is not declared: a candidate is a parameter whose terms selection may drop",
                11);
    check_error(error_of<ModelError>("candidate y\n"),
                "'y' is a state: a candidate is a parameter whose terms selection may drop", 11);
    check_error(error_of<ModelError>("param m = 2 fixed\ncandidate m\n"),
                "'m' is fixed (line 6): a known parameter cannot be a candidate", 11, 7);
    check_error(error_of<ParseError>("library v' y\n"),
                "expected ':' after the equation, as in 'library v': y^2, y^3'", 12);
    check_error(error_of<ParseError>("library v':\n"), "expected a comma-separated list of terms",
                12);
    check_error(error_of<ParseError>("candidate\n"),
                "expected a comma-separated list of parameters", 10);
  }

  TEST_CASE("a state's derivative in two equations needs a label") {
    const auto e = error_from<ModelError>([] {
      momentid::parse_model("state y\nparam a\ny' = a*y\n2*y' = 2*a*y\nlibrary y': y^2\n",
                            "test.mom");
    });
    CHECK(e.message() == "y' is in equations 1 and 2: label the one the terms join and name it");
  }

  TEST_CASE("the lagged equations name every library term the data cannot carry at once") {
    const Model m = parsed("library motion: y, v^2, v^3, x\n");
    // y and x measured, v not: v^2 and v^3 are no time derivatives of y.
    const auto e = error_from<ModelError>([&] {
      momentid::derive_lagged(m, {.measured = {true, false, true}});
    });
    CHECK(e.message() ==
          "2 terms of equation motion cannot be read from the data's channels (leave them out, or "
          "record the channels they need):\n"
          "  term '-motion_v2*v^2' of equation motion needs a column for v: it is not a time "
          "derivative of measured channels (v = y')\n"
          "  term '-motion_v3*v^3' of equation motion needs a column for v: it is not a time "
          "derivative of measured channels (v = y')");
    CHECK(e.location().line == 5);
  }
}
