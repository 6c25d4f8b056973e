#include <doctest/doctest.h>

#include "momentid/derive.hpp"
#include "momentid/model.hpp"

namespace {

const momentid::Model& duffing() {
  static const momentid::Model model = momentid::parse_model(R"(# comment line
model duffing "Forced Duffing oscillator"
state  y, v            # displacement, velocity
input  x
param  c = 0.5, k = 4, eps = 1
const  m = 2
y' = v
motion: m*v' = -c*v - k*y
               - eps*y^3 + x
multipliers motion: y, v, y^3, y*v^2
)",
                                                             "duffing.mom");
  return model;
}

}  // namespace

TEST_SUITE("parser") {
  TEST_CASE("a measured column of a derivative is a channel after the inputs") {
    using namespace momentid;
    const Model model = parse_model(R"(state y, v
input x
measured acc = y''   # the same as v'
param c, k
y' = v
v' = -c*v - k*y + x*abs(v)
)",
                                    "accelerometer.mom");
    REQUIRE(model.measured_derivatives().size() == 1);
    CHECK(model.measured_derivatives()[0].state == 1);
    CHECK(model.measured_derivatives()[0].written == "y''");
    CHECK(model.channel_names() == std::vector<std::string>{"y", "v", "x", "acc"});
    CHECK(model.variables()[3] == Variable{"acc", VariableKind::kDerivative, 0});
    CHECK(model.variables()[4].kind == VariableKind::kFunction);
    CHECK(model.measured_derivative_of(1) == 3);
    CHECK(model.measured_derivative_of(0) == -1);
    CHECK(model.channel_count() == 4);
    const std::string text = format_text(derive(model, {.degree = 1}));
    // E[y*v'] and E[v*v'] are read from the column, not eliminated.
    CHECK(text.find("E[y*acc]") != std::string::npos);
    CHECK(text.find("E[v*acc]") != std::string::npos);
  }

  TEST_CASE("declarations keep their order, kinds and exact values") {
    const momentid::Model& model = duffing();
    CHECK(model.name() == "duffing");
    CHECK(model.title() == "Forced Duffing oscillator");
    using momentid::VariableKind;
    CHECK(model.variables() == std::vector<momentid::Variable>{{"y", VariableKind::kState, 0},
                                                               {"v", VariableKind::kState, 1},
                                                               {"x", VariableKind::kInput, 0}});
    CHECK(model.channel_names() == std::vector<std::string>{"y", "v", "x"});
    CHECK(model.variable_index("x") == 2);
    CHECK(model.variable_index("k") == -1);
    REQUIRE(model.parameters().size() == 3);
    CHECK(*model.parameters()[0].value == GiNaC::numeric(1, 2));
    CHECK(model.parameters()[2].where.line == 5);
    CHECK(model.parameters()[2].where.column == 24);
    CHECK(*model.constants()[0].value == 2);
  }

  TEST_CASE("a parameter declared fixed keeps its value and says so") {
    const momentid::Model model = momentid::parse_model(
        "state y\ninput x\nparam a = 2 fixed, b, c = -0.5 fixed\ny' = -a*y - b*y^3 + c*x\n",
        "f.mom");
    const auto& p = model.parameters();
    REQUIRE(p.size() == 3);
    CHECK(p[0].fixed);
    CHECK(*p[0].value == 2);
    CHECK_FALSE(p[1].fixed);
    CHECK(p[2].fixed);
    CHECK(*p[2].value == GiNaC::numeric(-1, 2));
    // `fixed` is a word only after a value: it may still name a parameter.
    CHECK(momentid::parse_model("state y\nparam fixed = 1 fixed\ny' = -fixed*y\n", "g.mom")
              .parameters()[0]
              .fixed);
  }

  TEST_CASE("an equation becomes terms of lhs - rhs with constants substituted") {
    const momentid::Equation& eq = duffing().equations()[1];
    CHECK(eq.label == "motion");
    CHECK(eq.number == 2);
    CHECK(eq.where.line == 8);
    CHECK(eq.terms.size() == 5);
    const momentid::Model& model = duffing();
    const GiNaC::ex want =
        2 * model.derivative_symbol(1) + model.parameter_symbol(0) * model.state_symbol(1) +
        model.parameter_symbol(1) * model.state_symbol(0) +
        model.parameter_symbol(2) * GiNaC::pow(model.state_symbol(0), 3) - model.input_symbol(0);
    CHECK((eq.lhs - eq.rhs - want).expand().is_zero());
    for (const momentid::Term& t : eq.terms) {
      if (t.derivative >= 0) {
        CHECK(t.derivative == 1);
        CHECK(t.coefficient == 2);
        CHECK(t.parameter == -1);
      }
    }
  }

  TEST_CASE("a multipliers statement applies to its labelled equation") {
    const momentid::Model& model = duffing();
    REQUIRE(model.multipliers().size() == 1);
    CHECK(model.multipliers()[0].equation == "motion");
    std::vector<std::string> names;
    for (const auto& m : model.multipliers()[0].monomials) {
      momentid::Monomial full = m;
      full.resize(3);
      names.push_back(momentid::format_monomial(model, full));
    }
    CHECK(names == std::vector<std::string>{"y", "v", "y^3", "y*v^2"});
  }

  TEST_CASE("the model name defaults to the file name") {
    const momentid::Model model =
        momentid::parse_model("state y\ninput x\nparam a\ny' = -a*y + x\n", "dir/first.order.mom");
    CHECK(model.name() == "first");
  }

  TEST_CASE("numbers are read exactly") {
    CHECK(momentid::parse_exact_number("0.1") == GiNaC::numeric(1, 10));
    CHECK(momentid::parse_exact_number(".5") == GiNaC::numeric(1, 2));
    CHECK(momentid::parse_exact_number("4.") == 4);
    CHECK(momentid::parse_exact_number("1e-3") == GiNaC::numeric(1, 1000));
    CHECK(momentid::parse_exact_number("2.5E+2") == 250);
  }
}
