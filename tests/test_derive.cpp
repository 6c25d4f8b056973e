#include <doctest/doctest.h>

#include <algorithm>
#include <map>
#include <string>

#include "momentid/derive.hpp"
#include "momentid/estimate.hpp"
#include "momentid/json.hpp"
#include "momentid/lagged.hpp"
#include "momentid/model.hpp"
#include "test_support.hpp"

namespace {

using momentid::testing::error_from;
using momentid::testing::lagged_equation_text;
using momentid::testing::model_file;

using GiNaC::ex;
using momentid::derive;
using momentid::DeriveOptions;
using momentid::Model;
using momentid::MomentSystem;

// The model's symbol (state, input or parameter) called `name`.
ex sym(const Model& model, const std::string& name) {
  for (std::size_t i = 0; i < model.states().size(); ++i) {
    if (model.states()[i].name == name) return model.state_symbol(static_cast<int>(i));
  }
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    if (model.inputs()[i].name == name) return model.input_symbol(static_cast<int>(i));
  }
  const int p = model.parameter_index(name);
  REQUIRE_MESSAGE(p >= 0, name);
  return model.parameter_symbol(p);
}

ex E(const ex& monomial) { return momentid::expectation_of(monomial); }

// Replaces moments that the system's pure-data identities express through others, so that a
// hand-written equation can be compared with the derived one.
ex reduce(const MomentSystem& system, const ex& e) {
  GiNaC::exmap map;
  for (const momentid::DataIdentity& id : system.identities) {
    ex value = 0;
    for (const auto& [m, w] : id.value) value += w * momentid::moment_as_ex(*system.model, m);
    map[momentid::moment_as_ex(*system.model, id.moment)] = value;
  }
  return e.subs(map).expand();
}

// Checks that derived equation `row` equals `lhs = rhs` up to an overall sign, by subtraction.
void check_equation(const MomentSystem& system, std::size_t row, const ex& lhs, const ex& rhs) {
  REQUIRE(row < system.equations.size());
  const ex got = momentid::equation_as_ex(*system.model, system.equations[row]).expand();
  const ex want = reduce(system, lhs - rhs);
  INFO("derived:  ", got, " = 0");
  INFO("expected: ", want, " = 0");
  CHECK(((got - want).expand().is_zero() || (got + want).expand().is_zero()));
}

}  // namespace

TEST_SUITE("derive") {
  TEST_CASE("example 1 gives equation (3.3): a E[y^2] = E[y x]") {
    const Model model = model_file("kozin_example1.mom");
    const MomentSystem system = derive(model);
    REQUIRE(system.equations.size() == 1);
    const ex y = sym(model, "y"), x = sym(model, "x"), a = sym(model, "a");
    check_equation(system, 0, a * E(pow(y, 2)), E(y * x));
    CHECK(system.generic_rank == 1);
  }

  TEST_CASE("example 2 with multipliers y1, y2, y2^2 gives the three equations (3.7)") {
    const Model model = model_file("kozin_example2.mom");
    const MomentSystem system = derive(model);
    REQUIRE(system.equations.size() == 3);
    const ex y1 = sym(model, "y1"), y2 = sym(model, "y2"), x = sym(model, "x");
    const ex a = sym(model, "a"), b = sym(model, "b"), c = sym(model, "c");
    check_equation(system, 0, -a * E(pow(y2, 2)) + c * E(pow(y1, 2)), E(y1 * x));
    check_equation(system, 1, b * E(pow(y2, 2)), E(y2 * x));
    check_equation(system, 2, b * E(pow(y2, 3)) + c * E(pow(y2, 2) * y1), E(pow(y2, 2) * x));
    CHECK(system.generic_rank == 3);
  }

  TEST_CASE("reduces E[y1*y2'] to -E[y2^2] when y1' = y2") {
    const Model model = model_file("kozin_example2.mom");
    const MomentSystem system =
        derive(model, {.multipliers = momentid::parse_multiplier_list(model, "y1", "test")});
    const ex y1 = sym(model, "y1"), y2 = sym(model, "y2"), x = sym(model, "x");
    const ex a = sym(model, "a"), c = sym(model, "c");
    // a E[y1 y2'] + b E[y1 y2] + c E[y1^2] = E[y1 x] with E[y1 y2'] = -E[y2^2], E[y1 y2] = 0.
    check_equation(system, 0, a * -E(pow(y2, 2)) + c * E(pow(y1, 2)), E(y1 * x));
  }

  TEST_CASE("example 3 with y1, y2 on the second and y3, y4 on the fourth gives (3.9)") {
    const Model model = model_file("kozin_example3.mom");
    const MomentSystem system = derive(model);
    REQUIRE(system.equations.size() == 4);
    const ex y1 = sym(model, "y1"), y2 = sym(model, "y2"), y3 = sym(model, "y3"),
             y4 = sym(model, "y4"), x = sym(model, "x");
    const ex a = sym(model, "a"), b = sym(model, "b"), c = sym(model, "c"), d = sym(model, "d");
    // (3.9) as printed in the report, left side = right side.
    check_equation(system, 0, -E(pow(y2, 2)),
                   -b * E(pow(y1, 2)) + c * E(y1 * y4) + d * (E(y1 * y3) - E(pow(y1, 2))));
    check_equation(system, 1, 0,
                   -a * E(pow(y2, 2)) + c * (E(y4 * y2) - E(pow(y2, 2))) + d * E(y2 * y3));
    check_equation(system, 2, E(pow(y4, 2)) + E(x * y3),
                   -c * E(y2 * y3) + d * (E(pow(y3, 2)) - E(y1 * y3)));
    check_equation(system, 3, E(x * y4), c * (E(pow(y4, 2)) - E(y4 * y2)) - d * E(y1 * y4));
    CHECK(system.generic_rank == 4);
  }

  TEST_CASE("the pure-data identities of example 3 are listed and used") {
    const Model model = model_file("kozin_example3.mom");
    const MomentSystem system = derive(model);
    std::vector<std::string> identities;
    for (const auto& id : system.identities) {
      identities.push_back(momentid::format_moment(model, id.moment) + " = " +
                           momentid::format_combination(model, id.value));
    }
    CHECK(identities ==
          std::vector<std::string>{"E[y1*y2] = 0", "E[y2*y3] = -E[y1*y4]", "E[y3*y4] = 0"});
    for (const auto& m : system.moments) {
      const std::string name = momentid::format_moment(model, m);
      CHECK_MESSAGE((name != "E[y1*y2]" && name != "E[y2*y3]" && name != "E[y3*y4]"), name);
    }
  }

  TEST_CASE("duffing with degree 3 gives at least three independent equations in c, k, eps") {
    const Model model = model_file("duffing.mom");
    const MomentSystem system = derive(model, {.multipliers = {}, .degree = 3});
    CHECK(system.equations.size() == 9);
    CHECK(system.generic_rank == 3);
    CHECK(system.skipped.empty());
    const ex y = sym(model, "y"), v = sym(model, "v"), x = sym(model, "x");
    const ex c = sym(model, "c"), k = sym(model, "k"), eps = sym(model, "eps");
    // times y: E[y v'] = -E[v^2]; times y*v: E[y v v'] = -E[v^3]/2.
    check_equation(system, 0, k * E(pow(y, 2)) + eps * E(pow(y, 4)), E(y * x) + E(pow(v, 2)));
    check_equation(system, 1, c * E(pow(v, 2)), E(v * x));
    check_equation(system, 3, c * E(y * pow(v, 2)), E(y * v * x) + E(pow(v, 3)) / 2);
    check_equation(system, 7,
                   c * E(y * pow(v, 3)) + k * E(pow(y * v, 2)) + eps * E(pow(y, 4) * pow(v, 2)),
                   E(pow(v, 4)) / 3 + E(y * pow(v, 2) * x));
  }

  TEST_CASE("with rates, the identities leave the record's rates of change in the equations") {
    const Model model = model_file("duffing.mom");
    const MomentSystem system = derive(model, {.multipliers = {}, .degree = 3, .rates = true});
    const MomentSystem stationary = derive(model, {.multipliers = {}, .degree = 3});
    REQUIRE(system.equations.size() == stationary.equations.size());
    CHECK(system.generic_rank == 3);
    const ex y = sym(model, "y"), v = sym(model, "v"), x = sym(model, "x");
    const ex c = sym(model, "c"), k = sym(model, "k"), eps = sym(model, "eps");
    // E[(g)'] over (y, v, x).
    const auto R = [&](const momentid::Monomial& g) {
      return momentid::moment_as_ex(model, g.as_rate());
    };
    // times y: E[y v'] = E[(y*v)'] - E[v^2] and E[y*v] = E[(y^2)']/2;
    check_equation(system, 0, k * E(pow(y, 2)) + eps * E(pow(y, 4)) + c * R({2, 0, 0}) / 2,
                   E(y * x) + E(pow(v, 2)) - R({1, 1, 0}));
    // times v: E[v v'] = E[(v^2)']/2, E[y^3 v] = E[(y^4)']/4.
    check_equation(system, 1, c * E(pow(v, 2)) + k * R({2, 0, 0}) / 2 + eps * R({4, 0, 0}) / 4,
                   E(v * x) - R({0, 2, 0}) / 2);
    // The identities are listed in their stationary form, as without rates.
    REQUIRE(system.identities.size() == stationary.identities.size());
    for (std::size_t i = 0; i < system.identities.size(); ++i) {
      CHECK(system.identities[i].moment == stationary.identities[i].moment);
      CHECK(system.identities[i].value == stationary.identities[i].value);
    }
    // Rates are moments the equations need, written as derivatives.
    std::vector<std::string> rates;
    for (const auto& m : system.moments) {
      if (m.rate()) rates.push_back(momentid::format_moment(model, m));
    }
    CHECK(std::find(rates.begin(), rates.end(), "E[(y^2)']") != rates.end());
    CHECK(std::find(rates.begin(), rates.end(), "E[(y*v)']") != rates.end());
    const momentid::Monomial y_only{1, 0, 0};
    CHECK(momentid::format_moment(model, y_only.as_rate()) == "E[y']");
    CHECK(!y_only.rate());
    CHECK(y_only.as_rate().without_rate() == y_only);
    // A rate is listed among the moments of one degree more than its monomial (y^2, E[y'], v*x).
    CHECK(momentid::MomentOrder{}(momentid::Monomial{2, 0, 0}, y_only.as_rate()));
    CHECK(momentid::MomentOrder{}(y_only.as_rate(), momentid::Monomial{0, 1, 1}));
    CHECK(momentid::MomentOrder{}(momentid::Monomial{0, 0, 1}, y_only.as_rate()));
  }

  TEST_CASE("derivative moments known only in sums are eliminated by adding equations") {
    // Two dynamic states: E[v2*v1'] + E[v1*v2'] = 0 fixes neither alone, so equation 3 times v2
    // and equation 4 times v1 are added.
    const Model model = model_file("duffing_2dof.mom");
    const MomentSystem system =
        derive(model, {.multipliers = momentid::parse_multiplier_list(model, "v1, v2", "test")});
    REQUIRE(system.equations.size() == 3);
    const momentid::MomentEquation& sum = system.equations[2];
    REQUIRE(sum.sources.size() == 2);
    CHECK(sum.sources[0].equation == 2);
    CHECK(momentid::format_monomial(model, sum.sources[0].multiplier) == "v2");
    CHECK(sum.sources[1].equation == 3);
    CHECK(momentid::format_monomial(model, sum.sources[1].multiplier) == "v1");
    CHECK(sum.sources[0].factor == sum.sources[1].factor);
    const ex v1 = sym(model, "v1"), v2 = sym(model, "v2"), y1 = sym(model, "y1"),
             y2 = sym(model, "y2"), x = sym(model, "x");
    const ex lhs = sym(model, "c1") * E(v1 * v2) + sym(model, "k1") * E(y1 * v2) +
                   sym(model, "eps1") * E(pow(y1, 3) * v2) +
                   sym(model, "kc") * (E(y1 * v2) - E(y2 * v2)) + sym(model, "c2") * E(v1 * v2) +
                   sym(model, "k2") * E(y2 * v1) + sym(model, "eps2") * E(pow(y2, 3) * v1) +
                   sym(model, "kc") * (E(y2 * v1) - E(y1 * v1));
    check_equation(system, 2, lhs, E(v1 * x));
    CHECK(system.skipped.empty());
  }

  TEST_CASE("a multiplier that cannot be reduced is skipped with its reason") {
    const Model model = momentid::parse_model(R"(
state y1, y2
input x
param a, b
y1' = -a*y1 + y2
y2' = -b*y2 + x
)",
                                              "two.mom");
    const MomentSystem system =
        derive(model, {.multipliers = momentid::parse_multiplier_list(model, "y1, y2", "test")});
    // y1 on both equations and y2 on both reduce; y2 on the first and y1 on the second only
    // together.
    CHECK(system.equations.size() == 3);
    CHECK(system.skipped.empty());

    const Model lonely = momentid::parse_model(R"(
state y1, y2
input x
param a, b
y1' = -a*y1 + x
y2' = -b*y2 + y1
multipliers y2
)",
                                               "lonely.mom");
    const MomentSystem s2 = derive(lonely);
    REQUIRE(s2.skipped.size() == 1);
    CHECK(s2.skipped[0].equation == 0);
    CHECK(s2.skipped[0].reason ==
          "E[y2*y1'] is known only in the sum E[y2*y1'] + E[y1*y2'] (from E[d/dt y1*y2] = 0), "
          "and no combination of the chosen equations eliminates it");
    CHECK(s2.equations.size() == 1);
  }

  TEST_CASE("a derivative multiplied by an input is reported as irreducible") {
    const Model model = momentid::parse_model(R"(
state y
input x
param a
(1 + x)*y' = -a*y + x
multipliers y
)",
                                              "input.mom");
    const MomentSystem system = derive(model);
    REQUIRE(system.skipped.size() == 1);
    CHECK(system.skipped[0].reason ==
          "E[y*x*y'] multiplies an input by a derivative: no stationarity identity reduces it");
    CHECK(system.equations.empty());
  }

  TEST_CASE("a parameter in front of a derivative keeps the derivative moment in its coefficient") {
    const Model model = model_file("kozin_example2.mom");
    const MomentSystem system = derive(model, {.multipliers = {}, .degree = 2});
    CHECK(system.generic_rank == 3);
    CHECK(system.skipped.empty());
  }

  TEST_CASE("automatic multipliers raise the degree until every parameter is determined") {
    const Model model = model_file("cubic_first_order.mom");
    const MomentSystem system = derive(model);
    // y alone gives one equation in a and b; y^2 a second, but one that holds only odd moments,
    // which vanish for this symmetric system; y^3 gives the second usable one.
    CHECK(system.equations.size() == 3);
    CHECK(system.generic_rank == 2);
    CHECK(system.symmetric_rank == 2);
  }

  TEST_CASE("a row in which no parameter remains is skipped with what it says") {
    // Times 1: E[y2'] = 0 and E[y2] = 0 (since y1' = y2) remove b; left is 0 = E[x] - E[y1].
    const Model model = momentid::parse_model(R"(
state y1, y2
input x
param b
y1' = y2
y2' = -b*y2 - y1 + x
multipliers 1, y2
)",
                                              "zero.mom");
    const MomentSystem system = derive(model);
    REQUIRE(system.equations.size() == 1);
    CHECK(momentid::format_monomial(model, system.equations[0].sources[0].multiplier) == "y2");
    REQUIRE(system.skipped.size() == 1);
    CHECK(system.skipped[0].reason ==
          "no parameter remains: the equation says only 0 = -E[y1] + E[x]");
  }

  TEST_CASE("monomials up to degree 2 in two states") {
    std::vector<std::string> names;
    const Model model = model_file("kozin_4_1b.mom");
    for (const auto& m : momentid::monomials_up_to(2, 2)) {
      momentid::Monomial full = m;
      full.resize(3);
      names.push_back(momentid::format_monomial(model, full));
    }
    CHECK(names == std::vector<std::string>{"y1", "y2", "y1^2", "y1*y2", "y2^2"});
  }

  TEST_CASE("the text format shows equations, moments, identities and skipped multipliers") {
    const Model model = model_file("kozin_example2.mom");
    const std::string text = momentid::format_text(derive(model));
    CHECK(text ==
          "moment equations of kozin_example2 (Oscillator (Kozin & Kozin 1967, eq. 3.4))\n"
          "\n"
          "  1  [motion]*y1     -a*E[y2^2] + c*E[y1^2] = E[y1*x]\n"
          "  2  [motion]*y2     b*E[y2^2] = E[y2*x]\n"
          "  3  [motion]*y2^2   b*E[y2^3] + c*E[y1*y2^2] = E[y2^2*x]\n"
          "\n"
          "equations: 3 (independent: 3 of 3 parameters; 2 if odd moments vanish, as for "
          "symmetric systems)\n"
          "parameters: a, b, c\n"
          "moments needed: 7: E[y1^2], E[y1*x], E[y2^2], E[y2*x], E[y1*y2^2], E[y2^3], "
          "E[y2^2*x]\n"
          "identities used: 1\n"
          "  E[y1*y2] = 0\n"
          "multipliers skipped: 0\n");
  }

  TEST_CASE("the automatic multipliers reach the model's own degree") {
    // Van der Pol (mu*(1 - y^2)*v) is determined at degree 1 but estimated ten times better at
    // degree 3.
    const MomentSystem vdp = derive(momentid::testing::model_file("van_der_pol.mom"));
    CHECK(vdp.equations.size() ==
          derive(momentid::testing::model_file("van_der_pol.mom"), {.degree = 3}).equations.size());
  }

  TEST_CASE("the automatic multipliers leave equations to spare for the model's test") {
    // y' = -a*y + x is square at degree 1 (a*E[y^2] = E[y*x]); degree 2 adds only odd moments,
    // which vanish for symmetric data; degree 3 adds a*E[y^4] = E[y^3*x].
    const MomentSystem first = derive(momentid::testing::model_file("kozin_4_1a.mom"));
    CHECK(first.equations.size() == 3);
    CHECK(first.symmetric_rank == 1);
    CHECK(first.symmetric_rank_with_rhs == 2);
    // Two masses: degree 1 already gives 7 equations for 4 parameters, and stays there.
    const Model chain = momentid::parse_model(
        "state y1, v1, y2, v2\ninput x\nparam c, k, c2, k2\ny1' = v1\n"
        "v1' = -c*v1 - k*y1 - c2*(v1 - v2) - k2*(y1 - y2)\ny2' = v2\n"
        "v2' = -c2*(v2 - v1) - k2*(y2 - y1) + x\n",
        "chain.mom");
    const MomentSystem two = derive(chain);
    CHECK(two.equations.size() == 7);
    CHECK(two.symmetric_rank == 4);
    CHECK(two.symmetric_rank_with_rhs > 4);
  }

  TEST_CASE("abs and sign factors change sign with the states as their arguments do") {
    // Variables: y, v, x, then abs(v), sign(v), abs(y - 1), sign(y - 1).
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam c, f, k, a, b\ny' = v\n"
        "v' = -c*abs(v)*v - f*sign(v) - k*y - a*abs(y - 1) - b*sign(y - 1) + x\n",
        "p.mom");
    REQUIRE(model.variables().size() == 7);
    // A function knows its kind and its place among the model's functions.
    CHECK(model.variables()[5] ==
          momentid::Variable{"abs(y - 1)", momentid::VariableKind::kFunction, 2});
    CHECK(!model.variables()[5].channel());
    CHECK(model.channel_names() == std::vector<std::string>{"y", "v", "x"});
    using momentid::Parity;
    CHECK(momentid::parity(model, {0, 1, 0, 1, 0, 0, 0}) == Parity::kOdd);   // v*abs(v)
    CHECK(momentid::parity(model, {1, 0, 0, 0, 1, 0, 0}) == Parity::kEven);  // y*sign(v)
    CHECK(momentid::parity(model, {0, 0, 0, 0, 0, 1, 0}) == Parity::kNone);  // abs(y - 1)
    CHECK(momentid::parity(model, {0, 0, 0, 0, 0, 2, 0}) == Parity::kNone);  // (y - 1)^2
    CHECK(momentid::parity(model, {0, 1, 0, 0, 0, 0, 2}) == Parity::kOdd);   // v*sign(y - 1)^2
  }

  TEST_CASE("a kinematic equation of mixed degree does not start an endless identity search") {
    // y' = -y - y^3 + x relates moments of degree k to degree k + 2 without end; identities are
    // looked for only up to the equations' own degree.
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam c\ny' = -y - y^3 + x\nv' = -c*v + y\n", "loop.mom");
    const MomentSystem system = derive(model, {.degree = 1});
    CHECK(system.generic_rank == 1);
    REQUIRE(system.identities.size() == 1);
    CHECK(momentid::format_moment(model, system.identities[0].moment) + " = " +
              momentid::format_combination(model, system.identities[0].value) ==
          "E[y^4] = -E[y^2] + E[y*x]");
  }

  TEST_CASE("a degree that would build too many products is refused with the count") {
    std::string text = "state y1, y2, y3, y4, y5, y6, y7, y8\ninput x\nparam a\n";
    text += "y1' = -a*y1 + x\n";
    for (int i = 2; i <= 8; ++i) {
      const std::string n = std::to_string(i), previous = std::to_string(i - 1);
      text += "y" + n + "' = -a*y" + n + " + y" + previous + "\n";
    }
    const Model model = momentid::parse_model(text, "chain.mom");
    CHECK_THROWS_WITH_AS(derive(model, {.multipliers = {}, .degree = 8}),
                         "--degree 8 on 8 states would multiply 8 equations by 12869 monomials "
                         "each, more than 20000 products: use a lower degree or give "
                         "--multipliers",
                         momentid::UsageError);
  }

  TEST_CASE("notes say when the model cannot be stationary or an equation is not used") {
    const Model growing = momentid::parse_model(
        "state y, z\ninput x\nparam a\ny' = -a*y + x\nz' = 1\n", "growing.mom");
    const MomentSystem g =
        derive(growing, {.multipliers = momentid::parse_multiplier_list(growing, "y, z", "test")});
    CHECK(std::find(g.notes.begin(), g.notes.end(),
                    "the model cannot be stationary: a stationarity identity says 0 = 1") !=
          g.notes.end());

    const Model square = momentid::parse_model(
        "state y1, y2\ninput x\nparam a, b\ny1' = y2^2\ny2' = -a*y2 - b*y1 + x\n", "sq.mom");
    const MomentSystem sq = derive(square);
    CHECK(std::find(sq.notes.begin(), sq.notes.end(),
                    "stationarity requires E[y2^2] = 0, which only a zero signal satisfies: "
                    "check the parameter-free equations") != sq.notes.end());

    const Model twice = momentid::parse_model(
        "state y, v\ninput x\nparam c, k\ny' = v\nkin: 2*y' = 2*v\nv' = -c*v - k*y + x\n"
        "multipliers kin: y\nmultipliers y\n",
        "twice.mom");
    const MomentSystem t = derive(twice);
    CHECK(t.notes == std::vector<std::string>{
                         "equation kin gives y' again (equation 1 already does): it gives no "
                         "moment equations",
                         "the multipliers for equation kin are not used: it has no unknown "
                         "parameters"});
  }

  TEST_CASE("products that reduce to 0 = 0 are counted in a note") {
    const Model model = momentid::parse_model(
        "state y\ninput x\nparam a, k\nk*y' = k*x - a*y\nmultipliers 1, y\n", "z.mom");
    const MomentSystem system = derive(model);
    CHECK(system.equations.size() == 2);
    const Model redundant = momentid::parse_model(
        "state y, v\ninput x\nparam k, c\ny' = v\nk*y' = k*v\nv' = -c*v - k*y + x\n"
        "multipliers y\n",
        "r.mom");
    const MomentSystem r = derive(redundant);
    CHECK(std::find(r.notes.begin(), r.notes.end(),
                    "1 product reduces to 0 = 0 and gives no equation") != r.notes.end());
  }

  // The polynomial whose expectation is E[g''], for comparison by subtraction.
  ex second_derivative(const Model& model, const momentid::HeldInputCorrection& c) {
    ex sum = 0;
    for (const auto& [m, w] : c.second_derivative) {
      ex product = w;
      for (std::size_t i = 0; i < m.size(); ++i) {
        product *= pow(sym(model, model.variables()[i].name), m[i]);
      }
      sum += product;
    }
    return sum;
  }

  TEST_CASE(
      "the held-input corrections of E[v^2] and E[v*x] are E[g''] along the model, input held") {
    const Model model = model_file("duffing.mom");
    const ex y = sym(model, "y"), v = sym(model, "v"), x = sym(model, "x");
    const ex c = sym(model, "c"), k = sym(model, "k"), eps = sym(model, "eps");
    // E[y^2] (its derivative 2 y v holds no input) and E[x^2] (no state) are not corrected;
    // E[v^2], E[v*x] and E[y*v] (whose derivative v^2 + y v' holds x) are.
    const auto h = momentid::held_input_corrections(
        model, {{2, 0, 0}, {0, 2, 0}, {0, 1, 1}, {1, 1, 0}, {0, 0, 2}});
    CHECK(h.unavailable.empty());
    REQUIRE(h.moments.size() == 3);
    CHECK(h.moments[0].moment == momentid::Monomial{0, 2, 0});
    // (v^2)' = 2 v a, (v^2)'' = 2 a^2 + 2 v a' with a = x - c v - k y - eps y^3 and
    // a' = -c a - k v - 3 eps y^2 v (x held).
    const ex a = x - c * v - k * y - eps * pow(y, 3);
    const ex want = 2 * a * a + 2 * v * (-c * a - k * v - 3 * eps * y * y * v);
    const ex got = second_derivative(model, h.moments[0]);
    const ex diff = (got - want).expand();
    CHECK_MESSAGE(diff.is_zero(), got, " != ", want);
    // (v x)'' = x a' with x held.
    CHECK(h.moments[1].moment == momentid::Monomial{0, 1, 1});
    const ex held = x * (-c * a - k * v - 3 * eps * y * y * v);
    CHECK_MESSAGE((second_derivative(model, h.moments[1]) - held).expand().is_zero(),
                  second_derivative(model, h.moments[1]));
    CHECK(h.moments[2].moment == momentid::Monomial{1, 1, 0});
  }

  TEST_CASE("an unknown mass makes the held-input correction's weights rational in it") {
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam m, c, k\ny' = v\nm*v' = -c*v - k*y + x\n", "mass.mom");
    const auto h = momentid::held_input_corrections(model, {{0, 2, 0}});
    REQUIRE(h.moments.size() == 1);
    const ex m = sym(model, "m");
    bool found = false;
    for (const auto& term : h.moments[0].second_derivative) {
      const ex& weight = term.second;
      if (term.first == momentid::Monomial{0, 0, 2}) {
        found = true;
        CHECK_MESSAGE((weight - 2 / (m * m)).normal().is_zero(), weight);
      }
    }
    CHECK(found);
  }

  TEST_CASE("no held-input correction when the derivatives are not polynomials in the states") {
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam c, k\ny' = v\n(1 + y^2)*v' = -c*v - k*y + x\n", "r.mom");
    const auto h = momentid::held_input_corrections(model, {{0, 2, 0}});
    CHECK(h.moments.empty());
    CHECK(h.unavailable == "the derivatives of the states are not polynomials in the states");
  }
}

namespace {

Model oscillator(const std::string& force) {
  return momentid::parse_model(
      "state y, v\ninput x\nparam c, a, k\ny' = v\nv' = -c*v - " + force + " - k*y + x\n",
      "osc.mom");
}

}  // namespace

TEST_SUITE("derive lagged abs and sign") {
  TEST_CASE("drag reads abs(v)*v from a channel computed from the measured velocity") {
    const Model model = oscillator("a*abs(v)*v");
    const std::vector<momentid::Monomial> y{{1, 0, 0, 0}};
    const auto system = momentid::derive_lagged(model, {.instruments = y});
    REQUIRE(system.equations.size() == 1);
    CHECK(lagged_equation_text(system, 0) ==
          "c*C[y;v](s) + a*C[y;v*abs(v)](s) + k*C[y;y](s) = C[y;x](s) - C'[y;v](s)");
    CHECK(system.needed == std::vector<bool>{true, true, true, true});
    const std::string text = momentid::format_text(system);
    CHECK(text.find("channels read: y, v, x\ncomputed from them: abs(v)\n") != std::string::npos);
    const nlohmann::ordered_json json = momentid::json_value(system);
    CHECK(json["channels"] == nlohmann::ordered_json{"y", "v", "x"});
    CHECK(json["computed"] == nlohmann::ordered_json{"abs(v)"});
    CHECK(momentid::format_latex(system).find("C_{y,\\,v*\\lvert v\\rvert}(s)") !=
          std::string::npos);
  }

  TEST_CASE("a clearance spring abs(y)*y needs only y and the force") {
    const Model model = oscillator("a*abs(y)*y");
    const auto system = momentid::derive_lagged(model, {.measured = {true, false, true}});
    // The cube of y as well, which tells abs(y)*y from y, and the term's own abs(y)*y.
    CHECK(system.instruments ==
          std::vector<momentid::Monomial>{{1, 0, 0, 0}, {3, 0, 0, 0}, {1, 0, 0, 1}});
    REQUIRE(system.equations.size() == 3);
    CHECK(lagged_equation_text(system, 0) ==
          "c*C'[y;y](s) + a*C[y;y*abs(y)](s) + k*C[y;y](s) = C[y;x](s) - C''[y;y](s)");
    CHECK(lagged_equation_text(system, 1) ==
          "c*C'[y^3;y](s) + a*C[y^3;y*abs(y)](s) + k*C[y^3;y](s) = C[y^3;x](s) - C''[y^3;y](s)");
    CHECK(lagged_equation_text(system, 2) ==
          "c*C'[y*abs(y);y](s) + a*C[y*abs(y);y*abs(y)](s) + k*C[y*abs(y);y](s) = "
          "C[y*abs(y);x](s) - C''[y*abs(y);y](s)");
    CHECK(system.needed == std::vector<bool>{true, false, true, true});
    CHECK(system.derivatives == std::vector<std::string>{"v = y'"});
  }

  TEST_CASE("a function of a state without a column is refused, naming the term and the state") {
    const Model model = oscillator("a*abs(v)*v");
    const auto e = error_from<momentid::ModelError>([&] {
      momentid::derive_lagged(model, {.measured = {true, false, true}});
    });
    CHECK(e.message() ==
          "term 'a*v*abs(v)' of equation 2 needs a column for state v: the lagged equations "
          "compute abs(v) from the measured channels (give the record a column for v)");
    CHECK(e.location().line == 5);
    // sign(y)*v is measured sign(y) times the derivative of y, not a time derivative of y.
    const Model product = oscillator("a*sign(y)*v");
    const auto f = error_from<momentid::ModelError>([&] {
      momentid::derive_lagged(product, {.measured = {true, false, true}});
    });
    CHECK(f.message() ==
          "term 'a*v*sign(y)' of equation 2 needs a column for v: it is not a time derivative of "
          "measured channels (v = y')");
  }

  TEST_CASE("the noise correction leaves a channel inside abs or sign of the same moment alone") {
    // a*y^2*sign(v): y's noise is independent of sign(v + e), its power corrected; b*v^2*abs(v):
    // no polynomial corrects v's noise inside abs(v), so neither is v^2 corrected.
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam c, a, b, k\ny' = v\n"
        "v' = -c*v - a*y^2*sign(v) - b*abs(v)*v^2 - k*y + x\n",
        "noisy.mom");
    const std::vector<momentid::Monomial> y{{1, 0, 0, 0, 0}};
    const auto system =
        momentid::derive_lagged(model, {.first_lag = 3, .last_lag = 60, .instruments = y});
    // Channels: y, v, x, then sign(v) and abs(v) computed.
    const auto rows = momentid::lagged_rows(system, 0.01, {0, 1, 2, 3, 4}, {0.01, 0.02, 0});
    const momentid::LagTestFunction& phi = system.test_functions[0];
    const int lag = static_cast<int>(phi.centre);
    const auto weights = [&](std::size_t parameter) {
      std::map<std::string, double> out;
      for (const auto& [k, w] : rows.rows.a[0][parameter].moments) {
        if (rows.moments[k].max_lag() == lag) out[to_string(rows.moments[k])] += w / phi(lag);
      }
      return out;
    };
    const std::string at = "(t-" + std::to_string(lag) + ")";
    const auto a = weights(1);
    REQUIRE(a.size() == 2);
    CHECK(a.at("c0^2*c3*c0" + at) == doctest::Approx(1));
    CHECK(a.at("c3*c0" + at) == doctest::Approx(-0.01));
    // The moment of the correction is listed whatever the noise, here with weight 0.
    const auto b = weights(2);
    REQUIRE(b.size() == 2);
    CHECK(b.at("c1^2*c4*c0" + at) == doctest::Approx(1));
    CHECK(b.at("c4*c0" + at) == 0);
  }
}

TEST_SUITE("derive lagged default instruments") {
  // Variables y, v, x (and abs or sign of one): monomials {y, v, x[, f]}.
  TEST_CASE("odd terms take the state and its highest power") {
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam c, k, e\ny' = v\nv' = -c*v - k*y - e*y^3 + x\n", "d.mom");
    const auto system = momentid::derive_lagged(model, {.measured = {true, false, true}});
    CHECK(system.instruments == std::vector<momentid::Monomial>{{1, 0, 0}, {3, 0, 0}});
  }
  TEST_CASE("a parameter on an even term adds the square, on the input the input") {
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam c, k, q, e, b\ny' = v\n"
        "v' = -c*v - k*y - q*y^2 - e*y^3 + b*x\n",
        "d.mom");
    const auto system = momentid::derive_lagged(model, {.measured = {true, false, true}});
    CHECK(system.instruments ==
          std::vector<momentid::Monomial>{{1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {0, 0, 1}});
  }
  TEST_CASE("the highest power is the one the term is read as: y^2*v with v unmeasured is y^3") {
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nparam mu, k\ny' = v\nv' = mu*(1 - y^2)*v - k*y + x\n", "d.mom");
    CHECK(momentid::derive_lagged(model, {.measured = {true, false, true}}).instruments ==
          std::vector<momentid::Monomial>{{1, 0, 0}, {3, 0, 0}});
    // With v measured the term is read as it stands.
    CHECK(momentid::derive_lagged(model, {.measured = {true, true, true}}).instruments ==
          std::vector<momentid::Monomial>{{1, 0, 0}, {2, 0, 0}, {0, 1, 0}});
  }
  TEST_CASE("an instrument names a measured column by its name or the derivative it holds") {
    // Variables y, v, x, a: the report names the column `a`, the equations v' and y''.
    const Model model = momentid::parse_model(
        "state y, v\ninput x\nmeasured a = v'\nparam c, k\ny' = v\nv' = -c*v - k*y + x\n", "d.mom");
    for (const char* written : {"a", "v'", "y''", "dot(v)"}) {
      CAPTURE(written);
      CHECK(momentid::parse_instrument_list(model, written, "--instruments") ==
            std::vector<momentid::Monomial>{{0, 0, 0, 1}});
    }
    CHECK(momentid::parse_instrument_list(model, "a^2, y*a", "--instruments") ==
          std::vector<momentid::Monomial>{{0, 0, 0, 2}, {1, 0, 0, 1}});
    // A derivative no column holds is no instrument; multipliers never name a column.
    const auto message = [&](auto parse, const char* text) {
      return error_from<momentid::ModelError>([&] { parse(model, text, "--instruments"); })
          .message();
    };
    CHECK(message(momentid::parse_instrument_list, "y'") ==
          "an instrument must be a monomial in the states and inputs, such as y or y^3, found "
          "'y''");
    CHECK(message(momentid::parse_multiplier_list, "a") ==
          "'a' is a measured column, which equations do not name: write the derivative it "
          "holds, v'");
  }
  TEST_CASE("abs(v)*v is odd and abs(y) even, each term an instrument, a known input none") {
    const Model odd = oscillator("a*abs(v)*v");
    CHECK(momentid::derive_lagged(odd, {}).instruments ==
          std::vector<momentid::Monomial>{
              {1, 0, 0, 0}, {3, 0, 0, 0}, {0, 1, 0, 0}, {0, 3, 0, 0}, {0, 1, 0, 1}});
    const Model even = oscillator("a*abs(y)");
    CHECK(momentid::derive_lagged(even, {}).instruments ==
          std::vector<momentid::Monomial>{{1, 0, 0, 0},
                                          {2, 0, 0, 0},
                                          {3, 0, 0, 0},
                                          {0, 1, 0, 0},
                                          {0, 2, 0, 0},
                                          {0, 3, 0, 0},
                                          {0, 0, 0, 1}});
  }
}
