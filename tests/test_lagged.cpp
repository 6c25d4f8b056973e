// Lagged moment equations: terms as cross-moment functions of the lag, unmeasured states through
// kinematic equations, the stencils for the lag derivatives, and the errors for terms the data
// cannot give.

#include <doctest/doctest.h>

#include <cmath>
#include <string>

#include "momentid/estimate.hpp"
#include "momentid/lagged.hpp"
#include "test_support.hpp"

namespace {

using momentid::testing::error_from;
using momentid::testing::lagged_equation_text;
using momentid::testing::model_file;

}  // namespace

TEST_SUITE("lagged") {
  TEST_CASE(
      "the Duffing equation with y(t-s) needs only y and x, velocity through lag derivatives") {
    const momentid::Model model = model_file("duffing.mom");
    const auto system = momentid::derive_lagged(model, {.measured = {true, false, true}});
    REQUIRE(system.equations.size() == 2);  // instruments y and y^3
    CHECK(lagged_equation_text(system, 0) ==
          "c*C'[y;y](s) + k*C[y;y](s) + eps*C[y;y^3](s) = C[y;x](s) - C''[y;y](s)");
    CHECK(lagged_equation_text(system, 1) ==
          "c*C'[y^3;y](s) + k*C[y^3;y](s) + eps*C[y^3;y^3](s) = C[y^3;x](s) - C''[y^3;y](s)");
    CHECK(system.needed == std::vector<bool>{true, false, true});
    CHECK(system.derivatives == std::vector<std::string>{"v = y'"});
  }

  TEST_CASE("a power of y times y' becomes the lag derivative of a higher power") {
    // Van der Pol: mu*(1 - y^2)*v = mu*(y' - (y^3)'/3).
    const momentid::Model model = model_file("van_der_pol.mom");
    const std::vector<momentid::Monomial> y{{1, 0, 0}};
    const auto system =
        momentid::derive_lagged(model, {.instruments = y, .measured = {true, false, true}});
    CHECK(lagged_equation_text(system, 0) ==
          "mu*(C'[y;y](s) - 1/3*C'[y;y^3](s)) - k*C[y;y](s) = -C[y;x](s) + C''[y;y](s)");
  }

  TEST_CASE("with every channel measured, derivative terms are lag derivatives of the columns") {
    const momentid::Model model = model_file("kozin_4_1a.mom");
    const auto system = momentid::derive_lagged(model, {.first_lag = 3, .last_lag = 42});
    REQUIRE(system.equations.size() == 1);
    CHECK(lagged_equation_text(system, 0) == "a*C[y;y](s) = C[y;x](s) - C'[y;y](s)");
  }

  TEST_CASE("a term the data cannot give is a located error naming the missing column") {
    const momentid::Model model = model_file("cubic_damping.mom");
    const auto e = error_from<momentid::ModelError>([&] {
      momentid::derive_lagged(model, {.measured = {true, false, true}});
    });
    CHECK(e.message() ==
          "term 'c3*v^3' of equation 2 needs a column for v: it is not a time derivative of "
          "measured channels (v = y')");
    CHECK(e.location().line == 7);
    const momentid::Model two = model_file("duffing_2dof.mom");
    const auto f = error_from<momentid::ModelError>([&] {
      momentid::derive_lagged(two, {.measured = {true, false, false, false, true}});
    });
    CHECK(f.message() ==
          "term '-kc*y2' of equation mass1 needs a column for state y2 (no kinematic equation "
          "such as y' = y2 defines it)");
  }

  TEST_CASE("an acceleration column alone reads y and v as its integrals, differentiated away") {
    const momentid::Model model = momentid::parse_model(
        "state y, v\ninput x\nmeasured a = v'\nparam c, k\nconst m = 2\n"
        "y' = v\nm*v' = -c*v - k*y + x\n",
        "acceleration.mom");
    // Variables y, v, x, a: the force and the acceleration measured.
    const auto system = momentid::derive_lagged(model, {.measured = {false, false, true, true}});
    CHECK(system.derivatives == std::vector<std::string>{"y'' = a", "v' = a"});
    CHECK(system.instruments == std::vector<momentid::Monomial>{{0, 0, 0, 1}});
    REQUIRE(system.equations.size() == 1);
    // The equation's second derivative in s: C[y;a] = C''[y;y], C[v;a] = C'[y;y].
    CHECK(lagged_equation_text(system, 0) ==
          "c*C'[a;a](s) + k*C[a;a](s) = -2*C''[a;a](s) + C''[a;x](s)");
    CHECK(system.needed == std::vector<bool>{false, false, true, true});
    // With the velocity measured as well, y is its integral: one derivative clears it.
    const auto velocity = momentid::derive_lagged(model, {.measured = {false, true, true, true}});
    CHECK(velocity.derivatives == std::vector<std::string>{"y' = v"});
    CHECK(lagged_equation_text(velocity, 0) ==
          "c*C'[v;v](s) + k*C[v;v](s) = -2*C'[v;a](s) + C'[v;x](s)");
  }

  TEST_CASE("a power of a state read only through its derivative names the state and --integrate") {
    const momentid::Model model = model_file("duffing_accelerometer.mom");
    const auto e = error_from<momentid::FormStatesError>([&] {
      momentid::derive_lagged(model, {.measured = {false, false, true, true}});
    });
    const std::string text = e.text([](const std::string& field) { return "--" + field; });
    CHECK(text.substr(text.find(": term") + 2) ==
          "term 'eps*y^3' of equation 2 needs a column for state 'y': the record shows it only "
          "through 'a' (y'' = a), which gives the terms linear in y alone (give the record a "
          "column 'y', or form y from 'a' with --integrate y)");
    CHECK(e.location().line == 9);
    CHECK(e.states() == std::vector<std::string>{"y"});  // what identify forms by default
  }

  TEST_CASE("lags that reach lag 0 or are too few for the test functions are refused") {
    const momentid::Model model = model_file("duffing.mom");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::derive_lagged(model, {.first_lag = 0, .last_lag = 60});
                      }).what()) ==
          "lags: the first lag must be at least 1 (white sensor noise biases lag 0), found 0");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::derive_lagged(model, {.first_lag = 5, .last_lag = 43});
                      }).what()) ==
          "lags: expected a last lag from 44 to 10000 (at least 40 lags, for the test functions "
          "to resolve), found 43");
    CHECK(std::string(
              error_from<momentid::UsageError>([&] {
                const std::vector<momentid::Monomial> v{{0, 1, 0}};
                momentid::derive_lagged(model, {.instruments = v, .measured = {true, false, true}});
              }).what()) == "instruments: v uses v, which the data do not have");
  }

  TEST_CASE("the test functions are smooth bumps kept a stencil's reach inside the lags") {
    const auto functions = momentid::lag_test_functions(3, 300);
    REQUIRE(functions.size() == 26);  // 20 across the window, 6 over its first fifth
    for (const momentid::LagTestFunction& phi : functions) {
      CHECK(phi.centre - phi.half_width >= 9 - 1e-9);  // 7 inside: the widest stencil's reach
      CHECK(phi.centre + phi.half_width <= 294 + 1e-9);
      CHECK(phi(phi.centre) == doctest::Approx(1));
      CHECK(phi(phi.centre - phi.half_width) == doctest::Approx(0));
      CHECK(phi(phi.centre + phi.half_width + 0.5) == 0);
    }
    // (1 - u^2)^8 at u = 1/2: 0.75^8.
    const momentid::LagTestFunction phi{.centre = 40, .half_width = 20, .power = 8};
    CHECK(phi(50) == doctest::Approx(std::pow(0.75, 8)).epsilon(1e-14));
    // A window too narrow for the narrow functions has only the wide ones.
    CHECK(momentid::lag_test_functions(3, 100).size() == 16);
  }

  TEST_CASE(
      "each row is the equation summed over lags, the stencils moved onto the test function") {
    // Row 0 (instrument y, first test function), coefficient of c: C'[y;y](s) summed with
    // weight phi(s), that is C[y;y](s) with weight sum_j w_j phi(s - j) / dt.
    const momentid::Model model = model_file("duffing.mom");
    const auto system = momentid::derive_lagged(model, {.measured = {true, false, true}});
    const double dt = 0.01;
    const auto rows = momentid::lagged_rows(system, dt, {0, -1, 1}, {});
    const momentid::LagTestFunction& phi = system.test_functions[0];
    const std::vector<double> w = momentid::stencil_weights(1);
    REQUIRE(w.size() == 5);
    std::map<int, double> got;
    for (const auto& [k, weight] : rows.rows.a[0][0].moments) {
      CHECK(to_string(rows.moments[k]).find("c0*c0(t-") == 0);
      got[rows.moments[k].max_lag()] += weight;
    }
    double sum_by_lag = 0, sum_by_parts = 0;
    for (int s = 3; s <= 300; ++s) {
      double want = 0;
      for (int j = -2; j <= 2; ++j) want += w[static_cast<std::size_t>(j + 2)] * phi(s - j) / dt;
      CHECK(got[s] == doctest::Approx(want).epsilon(1e-12).scale(1e-9));
      // The same for C(s) = cos(0.05 s): the sum of phi times the stencil of C.
      double stencil = 0;
      for (int j = -2; j <= 2; ++j)
        stencil += w[static_cast<std::size_t>(j + 2)] * std::cos(0.05 * (s + j)) / dt;
      sum_by_lag += phi(s) * stencil;
      sum_by_parts += got[s] * std::cos(0.05 * s);
    }
    CHECK(sum_by_parts == doctest::Approx(sum_by_lag).epsilon(1e-12));
  }

  TEST_CASE("the stencils differentiate polynomials of degree 2 reach exactly") {
    // Orders 0..3, reaches 2 (the five-point stencils) and 6 (the wide ones): exact for every
    // power up to degree 2 reach, at a point between the samples.
    for (const int reach : {momentid::kStencilReach, momentid::kWideStencilReach}) {
      for (int order = 0; order <= momentid::kMaxLagOrder; ++order) {
        const std::vector<double> w = momentid::stencil_weights(order, reach);
        const int r = momentid::stencil_reach(order, reach);
        REQUIRE(static_cast<int>(w.size()) == 2 * r + 1);
        for (int degree = 0; degree <= 2 * reach; ++degree) {
          const double s = 0.7;
          double got = 0, size = 0;
          for (int j = -r; j <= r; ++j) {
            got += w[j + r] * std::pow(s + j, degree);
            size += std::abs(w[j + r] * std::pow(s + j, degree));
          }
          double want = 0;  // d^order/ds^order s^degree
          if (degree >= order) {
            want = std::pow(s, degree - order);
            for (int i = 0; i < order; ++i) want *= degree - i;
          }
          INFO("reach ", reach, ", order ", order, ", degree ", degree);
          CHECK(std::abs(got - want) < 1e-12 * std::max(1.0, size));
        }
      }
    }
    // The five-point weights themselves.
    const std::vector<double> second = momentid::stencil_weights(2);
    const std::vector<double> want{-1.0 / 12, 16.0 / 12, -30.0 / 12, 16.0 / 12, -1.0 / 12};
    for (std::size_t j = 0; j < want.size(); ++j) CHECK(second[j] == doctest::Approx(want[j]));
  }

  TEST_CASE("a lagged moment puts the instrument s + j rows back, normalised") {
    const momentid::Moment m = momentid::lagged_moment({1, 0, 0}, {3, 0, 0}, 7);
    CHECK(to_string(m) == "c0^3*c0(t-7)");
    CHECK(m.max_lag() == 7);
  }

  TEST_CASE("powers of a noisy channel become Hermite polynomials in its noise variance") {
    // eps*C[y^3;y^3](s) with noise of variance v on y: E[(y^3 - 3vy)(t-s) (y^3 - 3vy)(t)].
    const momentid::Model model = model_file("duffing.mom");
    const std::vector<momentid::Monomial> cube{{3, 0, 0}};
    const auto system = momentid::derive_lagged(
        model,
        {.first_lag = 3, .last_lag = 60, .instruments = cube, .measured = {true, false, true}});
    const double v = 0.01;
    // Channels: y is 0, x is 1 (v is not read).
    const auto rows = momentid::lagged_rows(system, 0.01, {0, -1, 1}, {v, 0});
    REQUIRE(rows.rows.a.size() == system.test_functions.size());
    // The row of the first test function at a lag where it is not zero, divided by phi there.
    const momentid::LagTestFunction& phi = system.test_functions[0];
    const int lag = static_cast<int>(phi.centre);
    std::map<std::string, double> eps;
    for (const auto& [k, w] : rows.rows.a[0][2].moments) {
      if (rows.moments[k].max_lag() == lag) eps[to_string(rows.moments[k])] += w / phi(lag);
    }
    CHECK(rows.rows.a[0][2].constant == 0);
    REQUIRE(eps.size() == 4);
    const std::string at = "(t-" + std::to_string(lag) + ")";
    CHECK(eps["c0^3*c0^3" + at] == doctest::Approx(1));
    CHECK(eps["c0*c0^3" + at] == doctest::Approx(-3 * v));
    CHECK(eps["c0^3*c0" + at] == doctest::Approx(-3 * v));
    CHECK(eps["c0*c0" + at] == doctest::Approx(9 * v * v));
    // Without noise the same moments, in the same order, with zero weights for the corrections.
    const auto clean = momentid::lagged_rows(system, 0.01, {0, -1, 1}, {});
    CHECK(clean.moments == rows.moments);
  }
}
