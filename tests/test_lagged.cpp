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
using momentid::testing::model_file;

// The text of equation `i`: everything after the source column.
std::string equation_text(const momentid::LaggedSystem& system, std::size_t i) {
  const std::string text = momentid::format_text(system);
  std::size_t at = 0;
  for (std::size_t line = 0; line < 3 + i; ++line) at = text.find('\n', at) + 1;
  const std::string line = text.substr(at, text.find('\n', at) - at);
  const std::size_t source = line.find("(t-s)");
  REQUIRE(source != std::string::npos);
  return line.substr(line.find_first_not_of(' ', source + 5));
}

}  // namespace

TEST_SUITE("lagged") {
  TEST_CASE(
      "the Duffing equation with y(t-s) needs only y and x, velocity through lag derivatives") {
    const momentid::Model model = model_file("duffing.mom");
    const auto system = momentid::derive_lagged(model, {.measured = {true, false, true}});
    REQUIRE(system.equations.size() == 2);  // instruments y and y^3
    CHECK(equation_text(system, 0) ==
          "c*C'[y;y](s) + k*C[y;y](s) + eps*C[y;y^3](s) = C[y;x](s) - C''[y;y](s)");
    CHECK(equation_text(system, 1) ==
          "c*C'[y^3;y](s) + k*C[y^3;y](s) + eps*C[y^3;y^3](s) = C[y^3;x](s) - C''[y^3;y](s)");
    CHECK(system.needed == std::vector<bool>{true, false, true});
    CHECK(system.derivatives == std::vector<std::string>{"v = y'"});
    CHECK(system.max_order == 2);
  }

  TEST_CASE("a power of y times y' becomes the lag derivative of a higher power") {
    // Van der Pol: mu*(1 - y^2)*v = mu*(y' - (y^3)'/3).
    const momentid::Model model = model_file("van_der_pol.mom");
    const std::vector<momentid::Monomial> y{{1, 0, 0}};
    const auto system =
        momentid::derive_lagged(model, {.instruments = y, .measured = {true, false, true}});
    CHECK(equation_text(system, 0) ==
          "mu*(C'[y;y](s) - 1/3*C'[y;y^3](s)) - k*C[y;y](s) = -C[y;x](s) + C''[y;y](s)");
  }

  TEST_CASE("with every channel measured, derivative terms are lag derivatives of the columns") {
    const momentid::Model model = model_file("kozin_4_1a.mom");
    const auto system = momentid::derive_lagged(model, {.first_lag = 3, .last_lag = 5});
    REQUIRE(system.equations.size() == 1);
    CHECK(equation_text(system, 0) == "a*C[y;y](s) = C[y;x](s) - C'[y;y](s)");
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

  TEST_CASE("lags that the stencils would take to lag 0 are refused") {
    const momentid::Model model = model_file("duffing.mom");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::derive_lagged(model, {.first_lag = 2, .last_lag = 9});
                      }).what()) ==
          "lags: the first lag must be at least 3 so that the lag derivatives (stencils reaching "
          "2 lags either side) do not touch lag 0, found 2");
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::derive_lagged(model, {.first_lag = 5, .last_lag = 4});
                      }).what()) == "lags: expected a last lag from 5 to 10000, found 4");
    CHECK(std::string(
              error_from<momentid::UsageError>([&] {
                const std::vector<momentid::Monomial> v{{0, 1, 0}};
                momentid::derive_lagged(model, {.instruments = v, .measured = {true, false, true}});
              }).what()) == "instruments: v uses v, which the data do not have");
  }

  TEST_CASE("the stencils differentiate polynomials of degree 4 exactly") {
    // Central stencils of error O(h^4) are exact for polynomials up to degree 4 (order 3:
    // degree 5 less its order... checked up to 4 for all).
    for (int order = 0; order <= momentid::kMaxLagOrder; ++order) {
      const std::vector<double> w = momentid::stencil_weights(order);
      const int reach = momentid::kStencilReach[order];
      REQUIRE(static_cast<int>(w.size()) == 2 * reach + 1);
      for (int degree = 0; degree <= 4; ++degree) {
        const double s = 0.7;
        double got = 0;
        for (int j = -reach; j <= reach; ++j) got += w[j + reach] * std::pow(s + j, degree);
        double want = 0;  // d^order/ds^order s^degree
        if (degree >= order) {
          want = std::pow(s, degree - order);
          for (int i = 0; i < order; ++i) want *= degree - i;
        }
        INFO("order ", order, ", degree ", degree);
        CHECK(std::abs(got - want) < 1e-12);
      }
    }
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
        {.first_lag = 3, .last_lag = 3, .instruments = cube, .measured = {true, false, true}});
    const double v = 0.01;
    // Channels: y is 0, x is 1 (v is not read).
    const auto rows = momentid::lagged_rows(system, 0.01, {0, -1, 1}, {v, 0});
    REQUIRE(rows.rows.a.size() == 1);
    std::map<std::string, double> eps;
    for (const auto& [k, w] : rows.rows.a[0][2].moments) eps[to_string(rows.moments[k])] += w;
    CHECK(rows.rows.a[0][2].constant == 0);
    REQUIRE(eps.size() == 4);
    CHECK(eps["c0^3*c0^3(t-3)"] == doctest::Approx(1));
    CHECK(eps["c0*c0^3(t-3)"] == doctest::Approx(-3 * v));
    CHECK(eps["c0^3*c0(t-3)"] == doctest::Approx(-3 * v));
    CHECK(eps["c0*c0(t-3)"] == doctest::Approx(9 * v * v));
    // Without noise the same moments, in the same order, with zero weights for the corrections.
    const auto clean = momentid::lagged_rows(system, 0.01, {0, -1, 1}, {});
    CHECK(clean.moments == rows.moments);
  }
}
