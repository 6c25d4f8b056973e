#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/json.hpp"
#include "momentid/estimate.hpp"
#include "momentid/random.hpp"
#include "solve/delta_method.hpp"
#include "solve/distributions.hpp"
#include "solve/linear_system.hpp"
#include "solve/long_run.hpp"
#include "test_support.hpp"

namespace {

using momentid::Estimate;
using momentid::MomentEstimates;
using momentid::MomentRows;
using momentid::Monomial;
using momentid::Status;

// Means of `moments` moments over `batches` batches of standard normal values around `center`
// (one per moment), the overall mean their average, over 100 intervals per batch.
MomentEstimates random_estimates(const std::vector<double>& center, std::size_t batches,
                                 std::uint64_t seed) {
  momentid::PortableRandom random(seed, 0);
  MomentEstimates out;
  out.mean.assign(center.size(), 0.0);
  for (std::size_t b = 0; b < batches; ++b) {
    std::vector<double>& means = out.batch_means.emplace_back();
    for (std::size_t k = 0; k < center.size(); ++k) {
      means.push_back(center[k] + random.normal());
      out.mean[k] += means.back() / static_cast<double>(batches);
    }
  }
  out.intervals = 100 * batches;
  return out;
}

// The bits of a double, so that NaN equals NaN and 0 differs from -0.
std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

void check_same(const std::vector<momentid::ParameterEstimate>& a,
                const std::vector<momentid::ParameterEstimate>& b) {
  REQUIRE(a.size() == b.size());
  for (std::size_t p = 0; p < a.size(); ++p) {
    INFO(a[p].name);
    CHECK(bits(a[p].estimate) == bits(b[p].estimate));
    CHECK(bits(a[p].std_error) == bits(b[p].std_error));
    CHECK(bits(a[p].ci_low) == bits(b[p].ci_low));
    CHECK(bits(a[p].ci_high) == bits(b[p].ci_high));
  }
}

void check_same(const std::vector<std::vector<double>>& a,
                const std::vector<std::vector<double>>& b) {
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    REQUIRE(a[i].size() == b[i].size());
    for (std::size_t j = 0; j < a[i].size(); ++j) CHECK(bits(a[i][j]) == bits(b[i][j]));
  }
}

// Every number of the two fits is the same to the last bit.
void check_same(const momentid::Fit& a, const momentid::Fit& b) {
  check_same(a.parameters, b.parameters);
  check_same(a.correlation, b.correlation);
  CHECK(bits(a.dof) == bits(b.dof));
  CHECK(bits(a.objective) == bits(b.objective));
}

// Every number of the two estimates is the same to the last bit.
void check_same(const Estimate& a, const Estimate& b) {
  CHECK(a.status == b.status);
  CHECK(a.message == b.message);
  check_same(a.least_squares, b.least_squares);
  REQUIRE(a.optimal.has_value() == b.optimal.has_value());
  if (a.optimal) check_same(*a.optimal, *b.optimal);
  check_same(a.error_batches, b.error_batches);
  CHECK(bits(a.condition) == bits(b.condition));
  CHECK(bits(a.j_statistic.value_or(-1)) == bits(b.j_statistic.value_or(-1)));
  CHECK(bits(a.j_pvalue.value_or(-1)) == bits(b.j_pvalue.value_or(-1)));
  CHECK(a.warnings == b.warnings);
  REQUIRE(a.identities.size() == b.identities.size());
  for (std::size_t i = 0; i < a.identities.size(); ++i) {
    CHECK(a.identities[i].identity == b.identities[i].identity);
    CHECK(bits(a.identities[i].violation) == bits(b.identities[i].violation));
    CHECK(bits(a.identities[i].z) == bits(b.identities[i].z));
  }
}

// The Duffing oscillator's equations for multipliers up to degree 2 and random estimates of
// their moments around 1 (a generic, overdetermined system), 40 batches.
struct DuffingCase {
  momentid::Model model = momentid::testing::model_file("duffing.mom");
  momentid::MomentSystem system = momentid::derive(model, {.degree = 2});
  std::vector<Monomial> moments = momentid::moments_to_estimate(system);
  MomentEstimates estimates =
      random_estimates(std::vector<double>(moments.size(), 1.0), 40, /*seed=*/3);
};

// Rows theta = b_r for b = the moments (one parameter), with coefficients `a`.
MomentRows proportional_rows(const std::vector<double>& a) {
  MomentRows rows;
  for (std::size_t r = 0; r < a.size(); ++r) {
    rows.a.push_back({{a[r], {}}});
    rows.b.push_back({0.0, {{r, 1.0}}});
  }
  return rows;
}

}  // namespace

TEST_SUITE("solve") {
  TEST_CASE("distribution functions match tabulated values") {
    // Tabulated critical values; the functions are accurate far beyond the 1e-9 asked here.
    CHECK(momentid::student_t_quantile(0.975, 49) ==
          doctest::Approx(2.00957523712924).epsilon(1e-9));
    CHECK(momentid::student_t_quantile(0.975, 4) ==
          doctest::Approx(2.77644510519779).epsilon(1e-9));
    CHECK(momentid::f_upper_tail(3.3258345304130112, 5, 10) == doctest::Approx(0.05).epsilon(1e-9));
    CHECK(momentid::f_upper_tail(2.0, 30, 51) == doctest::Approx(0.0143130715165126).epsilon(1e-9));
  }

  // m = 30 equations b_r = mu_r in q = 2 parameters (a fixed), from B Gaussian batch means with
  // correlated components, repeated 1000 times: the squared errors of the optimally weighted
  // estimate over its reported variances, and the J test's rejections at the 5% level.
  struct Calibration {
    double ratio[2] = {0, 0};
    int rejections = 0;
  };
  Calibration gmm_calibration(std::size_t batches) {
    constexpr std::size_t m = 30, repeats = 1000;
    const double theta[2] = {1.0, -2.0};
    momentid::PortableRandom random(7, 0);
    std::vector<std::vector<double>> a(m, std::vector<double>(2)), mix(m, std::vector<double>(m));
    for (auto& row : a) {
      for (double& x : row) x = random.normal();
    }
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t j = 0; j < m; ++j) mix[i][j] = (i == j) + random.normal() / std::sqrt(m);
    }
    momentid::MomentRows rows;
    for (std::size_t r = 0; r < m; ++r) {
      rows.a.push_back({{a[r][0], {}}, {a[r][1], {}}});
      rows.b.push_back({0.0, {{r, 1.0}}});
    }
    double squared_error[2] = {0, 0}, variance[2] = {0, 0};
    Calibration out;
    for (std::size_t k = 0; k < repeats; ++k) {
      momentid::MomentEstimates estimates;
      estimates.mean.assign(m, 0.0);
      for (std::size_t b = 0; b < batches; ++b) {
        std::vector<double> z(m), mean(m);
        for (double& x : z) x = random.normal();
        for (std::size_t i = 0; i < m; ++i) {
          mean[i] = a[i][0] * theta[0] + a[i][1] * theta[1];
          for (std::size_t j = 0; j < m; ++j) mean[i] += mix[i][j] * z[j];
          estimates.mean[i] += mean[i] / static_cast<double>(batches);
        }
        estimates.batch_means.push_back(mean);
      }
      const momentid::Estimate e = momentid::solve_rows(rows, {"p", "q"}, estimates, {.gmm = true});
      REQUIRE(e.optimal.has_value());
      REQUIRE(e.optimal->parameters.size() == 2);
      for (std::size_t p = 0; p < 2; ++p) {
        squared_error[p] += std::pow(e.optimal->parameters[p].estimate - theta[p], 2) / repeats;
        variance[p] += std::pow(e.optimal->parameters[p].std_error, 2) / repeats;
      }
      REQUIRE(e.j_pvalue.has_value());
      out.rejections += *e.j_pvalue < 0.05;
    }
    for (std::size_t p = 0; p < 2; ++p) out.ratio[p] = squared_error[p] / variance[p];
    return out;
  }

  TEST_CASE("optimally weighted standard errors are calibrated for weights from few batches") {
    // With 80 batches for 30 equations, errors reported without the finite-sample correction
    // would be 1.55 times too small. The ratio of mean squared error to mean variance has a
    // relative standard error of about sqrt(2 / 1000) = 4.5%.
    const Calibration c = gmm_calibration(80);
    for (std::size_t p = 0; p < 2; ++p) {
      INFO("parameter ", p, ": squared error / reported variance ", c.ratio[p]);
      CHECK(std::abs(c.ratio[p] - 1) < 4 * 0.045);
    }
  }

  TEST_CASE("the J test rejects the right model at its level, with weights from the batches") {
    // 400 batches for 30 equations (with 80 the test is conservative, see solve_rows). The
    // rejection count is binomial(1000, 0.05), standard deviation 6.9.
    const Calibration c = gmm_calibration(400);
    INFO("J rejections at 5%: ", c.rejections);
    CHECK(std::abs(c.rejections - 50) < 4 * 6.9);
    for (std::size_t p = 0; p < 2; ++p) {
      INFO("parameter ", p, ": squared error / reported variance ", c.ratio[p]);
      CHECK(std::abs(c.ratio[p] - 1) < 4 * 0.045);
    }
  }

  TEST_CASE("JSON strings escape quotes and control characters and stay valid UTF-8") {
    CHECK(momentid::json_string("a\"b\\c\nd\x01") == "\"a\\\"b\\\\c\\nd\\u0001\"");
    CHECK(momentid::json_string("\xc3\xa9t\xff") == "\"\xc3\xa9t\\ufffd\"");
  }

  TEST_CASE("a result's JSON text: numbers that read back to the same double, null, valid UTF-8") {
    const double third = 1.0 / 3, tiny = 4.9406564584124654e-324;
    const nlohmann::ordered_json value = {
        {"numbers", momentid::json_value(
                        std::vector<double>{third, tiny, 0.1, 1e300, std::nan(""), -HUGE_VAL})},
        {"name", "\xc3\xa9t\xff"}};
    const std::string text = momentid::json_text(value);
    CHECK(text ==
          "{\n  \"numbers\": [\n    0.3333333333333333,\n    5e-324,\n    0.1,\n    1e+300,\n"
          "    null,\n    null\n  ],\n  \"name\": \"\xc3\xa9t\xef\xbf\xbd\"\n}\n");
    const nlohmann::ordered_json back = nlohmann::ordered_json::parse(text);
    CHECK(back["numbers"][0].get<double>() == third);
    CHECK(back["numbers"][1].get<double>() == tiny);
    CHECK(back["numbers"] == value["numbers"]);
  }

  TEST_CASE("solve reads each moment by its key: in any order and with others, the same bits") {
    DuffingCase c;
    // The moments backwards, with three the system does not need among them.
    std::vector<Monomial> moments = c.moments;
    std::reverse(moments.begin(), moments.end());
    moments.insert(moments.begin() + 2, {9, 0, 0});
    moments.insert(moments.begin() + 5, {0, 9, 0});
    moments.push_back({1, 1, 7});
    const MomentEstimates extra = random_estimates(std::vector<double>(3, 5.0), 40, 4);
    MomentEstimates shuffled = c.estimates;
    const auto place = [&](const Monomial& m) -> std::size_t {
      const auto at = std::find(c.moments.begin(), c.moments.end(), m);
      return at == c.moments.end() ? c.moments.size() : at - c.moments.begin();
    };
    std::size_t next_extra = 0;
    shuffled.mean.clear();
    for (std::vector<double>& batch : shuffled.batch_means) batch.clear();
    for (const Monomial& m : moments) {
      const std::size_t k = place(m);
      const bool own = k < c.moments.size();
      shuffled.mean.push_back(own ? c.estimates.mean[k] : extra.mean[next_extra]);
      for (std::size_t b = 0; b < shuffled.batch_means.size(); ++b) {
        shuffled.batch_means[b].push_back(own ? c.estimates.batch_means[b][k]
                                              : extra.batch_means[b][next_extra]);
      }
      next_extra += own ? 0 : 1;
    }
    for (const bool gmm : {false, true}) {
      const Estimate in_order = momentid::solve(c.system, c.moments, c.estimates, {.gmm = gmm});
      REQUIRE(in_order.status == Status::kOk);
      REQUIRE(!in_order.identities.empty());
      REQUIRE(in_order.optimal.has_value() == gmm);
      check_same(in_order, momentid::solve(c.system, moments, shuffled, {.gmm = gmm}));
    }
    const auto checks = momentid::check_identities(c.system, c.moments, c.estimates);
    const auto shuffled_checks = momentid::check_identities(c.system, moments, shuffled);
    REQUIRE(checks.size() == shuffled_checks.size());
    for (std::size_t i = 0; i < checks.size(); ++i) {
      CHECK(checks[i].identity == shuffled_checks[i].identity);
      CHECK(bits(checks[i].z) == bits(shuffled_checks[i].z));
    }
  }

  TEST_CASE("solve names a moment it needs and was not given") {
    DuffingCase c;
    const Monomial missing = c.moments[1];
    std::vector<Monomial> moments = c.moments;
    moments.erase(moments.begin() + 1);
    MomentEstimates estimates = c.estimates;
    estimates.mean.erase(estimates.mean.begin() + 1);
    for (auto& batch : estimates.batch_means) batch.erase(batch.begin() + 1);
    const auto e = momentid::testing::error_from<std::invalid_argument>(
        [&] { momentid::solve(c.system, moments, estimates); });
    CHECK(std::string(e.what()) == "solve: no estimate of " +
                                       momentid::format_moment(c.model, missing) +
                                       ", which the system needs");
    // A moment named twice, or names that are not one per estimate, are errors too.
    moments.push_back(moments.front());
    estimates.mean.push_back(estimates.mean.front());
    for (auto& batch : estimates.batch_means) batch.push_back(batch.front());
    CHECK(std::string(momentid::testing::error_from<std::invalid_argument>([&] {
                        momentid::solve(c.system, moments, estimates);
                      }).what()) ==
          "solve: " + momentid::format_moment(c.model, moments.front()) + " is named twice");
    MomentEstimates unnamed = c.estimates;
    unnamed.mean.push_back(0);
    CHECK_THROWS_AS(momentid::solve(c.system, c.moments, unnamed), std::invalid_argument);
  }

  TEST_CASE("solve_rows refuses rows that do not fit the parameters or the estimates") {
    MomentRows rows = proportional_rows({1, 2});
    const MomentEstimates estimates = random_estimates({1, 2}, 4, 5);
    CHECK_THROWS_AS(momentid::solve_rows(rows, {"p", "q"}, estimates), std::invalid_argument);
    rows.b[1].moments[0].first = 2;  // one past the estimates
    CHECK_THROWS_AS(momentid::solve_rows(rows, {"p"}, estimates), std::invalid_argument);
    // The same with a parameter fixed, whose terms move to the right-hand side first.
    rows.b[1].moments[0].first = 1;
    rows.a[0].push_back({1.0, {}});
    CHECK_THROWS_AS(momentid::solve_rows(rows, {"p"}, estimates, {.fixed = {0.5}}),
                    std::invalid_argument);
  }

  TEST_CASE("a fit's covariance is its errors times their correlation, 0 for a fixed parameter") {
    momentid::Fit fit;
    fit.parameters = {{"a", 1, 0.5}, {"b", 2, 2}, {"c", 3, 0, 3, 3, true, /*fixed=*/true}};
    fit.correlation = {{1, -0.25, NAN}, {-0.25, 1, NAN}, {NAN, NAN, NAN}};
    const std::vector<std::vector<double>> c = fit.covariance();
    CHECK(c[0][0] == 0.25);
    CHECK(c[1][1] == 4);
    CHECK(c[0][1] == -0.25);  // -0.25 * 0.5 * 2, exact
    CHECK(c[1][0] == -0.25);
    for (std::size_t i = 0; i < 3; ++i) CHECK((c[i][2] == 0 && c[2][i] == 0));
  }

  TEST_CASE("the least-squares objective is zero for a consistent system") {
    // b = a theta with theta = 0.75: every product exact, so that only the rounding of the
    // solution, of relative size 1e-16, is left in the residuals, squared 1e-32 of |b|^2.
    MomentEstimates estimates;
    estimates.mean = {0.75, 1.5, -2.25, 6};
    const Estimate e = momentid::solve_rows(proportional_rows({1, 2, -3, 8}), {"p"}, estimates);
    CHECK(e.least_squares.parameters[0].estimate == doctest::Approx(0.75).epsilon(1e-14));
    CHECK(e.least_squares.objective >= 0);
    CHECK(e.least_squares.objective < 1e-28);
  }

  TEST_CASE("the least-squares objective is the weighted sum of squared residuals") {
    // theta = 1, theta = 2, 2 theta = 6: theta = 15 / 6, residuals -1.5, -0.5, 1. Rows
    // normalised: theta = 1, 2, 3, theta = 2, residuals -1, 0, 1. Rounding only: 1e-14.
    MomentEstimates estimates;
    estimates.mean = {1, 2, 6};
    const MomentRows rows = proportional_rows({1, 1, 2});
    const Estimate plain = momentid::solve_rows(rows, {"p"}, estimates);
    CHECK(plain.least_squares.parameters[0].estimate == doctest::Approx(2.5).epsilon(1e-14));
    CHECK(plain.least_squares.objective == doctest::Approx(3.5).epsilon(1e-14));
    const Estimate normalised =
        momentid::solve_rows(rows, {"p"}, estimates, {.normalise_rows = true});
    CHECK(normalised.least_squares.objective == doctest::Approx(2.0).epsilon(1e-14));
    CHECK(!plain.optimal.has_value());

    // p + q = mu_0, p = mu_1, q = mu_2: with q fixed at 0 the fit is that of the rows without q,
    // and the objectives of the two parameter subsets compare.
    MomentRows both;
    for (std::size_t r = 0; r < 3; ++r) both.b.push_back({0.0, {{r, 1.0}}});
    both.a = {{{1.0, {}}, {1.0, {}}}, {{1.0, {}}, {0.0, {}}}, {{0.0, {}}, {1.0, {}}}};
    MomentRows only_p = both;
    for (auto& row : only_p.a) row.pop_back();
    const Estimate fixed =
        momentid::solve_rows(both, {"p", "q"}, estimates, {.fixed = {std::nullopt, 0.0}});
    const Estimate dropped = momentid::solve_rows(only_p, {"p"}, estimates);
    CHECK(fixed.least_squares.objective ==
          doctest::Approx(dropped.least_squares.objective).epsilon(1e-14));
    // p = (1 + 2) / 2, residuals -0.5, 0.5, 6.
    CHECK(dropped.least_squares.objective == doctest::Approx(36.5).epsilon(1e-14));
    const Estimate free = momentid::solve_rows(both, {"p", "q"}, estimates);
    CHECK(free.least_squares.objective < dropped.least_squares.objective);
  }

  TEST_CASE("T times the optimally weighted objective is Hansen's J, which the J test reports") {
    // Rows with constant coefficients and fewer than kMinSpectralBatches batches: the residual's
    // long-run covariance is then M (S / B) M', tr(W V) = j_dof, and the calibrated J is Hansen's
    // to rounding (1e-12).
    MomentRows rows = proportional_rows({1, 2, -1, 0.5});
    rows.a[1].push_back({1.0, {}});
    rows.a[3].push_back({-1.0, {}});
    rows.a[0].push_back({0.0, {}});
    rows.a[2].push_back({3.0, {}});
    const MomentEstimates estimates = random_estimates({1, 2, 3, 4}, 12, 6);
    REQUIRE(estimates.batch_means.size() < momentid::kMinSpectralBatches);
    const Estimate e = momentid::solve_rows(rows, {"p", "q"}, estimates, {.gmm = true});
    REQUIRE(e.optimal.has_value());
    REQUIRE(e.j_statistic.has_value());
    CHECK(e.j_dof == 2);
    CHECK(e.optimal->objective * static_cast<double>(e.intervals) ==
          doctest::Approx(*e.j_statistic).epsilon(1e-12));
  }

  TEST_CASE("the equations' batch series at any theta are the moments' through d g / d mu") {
    // Coefficients and right-hand sides that read several moments each, some twice: D g_mu(theta)'
    // summed from the columns' series equals the product at theta, to rounding.
    MomentRows rows;
    rows.a = {{{1.0, {{0, 2.0}, {3, -1.0}}}, {0.0, {{1, 0.5}}}},
              {{0.0, {{2, 1.0}, {2, 1.0}}}, {-2.0, {{0, 1.5}, {4, 3.0}}}},
              {{0.5, {}}, {0.0, {{3, -2.0}}}}};
    rows.b = {{0.0, {{4, 1.0}}}, {1.0, {{1, -1.0}, {0, 2.0}}}, {0.0, {{2, 0.25}}}};
    const MomentEstimates estimates = random_estimates({1, 2, 3, 4, 5}, 20, 5);
    const momentid::LinearSystem system =
        momentid::evaluate(rows, 2, estimates.mean, /*normalise_rows=*/false);
    const Eigen::MatrixXd deviations = momentid::batch_deviations(estimates);
    const momentid::EquationSeries series(system, deviations);
    for (const Eigen::Vector2d& theta : {Eigen::Vector2d(0, 0), Eigen::Vector2d(1.5, -0.7)}) {
      const Eigen::MatrixXd want =
          deviations * momentid::equations_jacobian(system, theta).transpose();
      const Eigen::MatrixXd got = series.at(theta);
      REQUIRE(got.rows() == 20);
      REQUIRE(got.cols() == 3);
      CHECK((got - want).norm() <= 1e-12 * want.norm());
    }
  }

  TEST_CASE("the result holds the batch series of the main estimate's errors") {
    // Their long-run covariance is the estimate's: the same numbers, to rounding (1e-12).
    MomentRows rows = proportional_rows({1, 2, -1, 0.5, 1.5});
    for (std::size_t r = 0; r < rows.a.size(); ++r) rows.a[r].push_back({r % 2 ? 1.0 : -0.5, {}});
    const MomentEstimates estimates = random_estimates({1, 2, 3, 4, 5}, 30, 8);
    for (const bool gmm : {false, true}) {
      const Estimate e = momentid::solve_rows(rows, {"p", "q"}, estimates, {.gmm = gmm});
      REQUIRE(e.optimal.has_value() == gmm);
      const auto& list = e.main().parameters;
      REQUIRE(list.size() == 2);
      REQUIRE(e.error_batches.size() == 30);
      Eigen::MatrixXd series(30, 2);
      for (Eigen::Index b = 0; b < 30; ++b) {
        for (Eigen::Index p = 0; p < 2; ++p) {
          series(b, p) = e.error_batches[static_cast<std::size_t>(b)][static_cast<std::size_t>(p)];
        }
      }
      const Eigen::MatrixXd covariance = momentid::long_run_covariance(series).covariance;
      for (Eigen::Index p = 0; p < 2; ++p) {
        CHECK(std::sqrt(covariance(p, p)) ==
              doctest::Approx(list[static_cast<std::size_t>(p)].std_error).epsilon(1e-12));
      }
    }
    // A fixed parameter has no error: a zero column.
    const Estimate fixed =
        momentid::solve_rows(rows, {"p", "q"}, estimates, {.fixed = {std::nullopt, 0.5}});
    REQUIRE(fixed.error_batches.size() == 30);
    for (const auto& batch : fixed.error_batches) {
      REQUIRE(batch.size() == 2);
      CHECK(batch[1] == 0);
    }
  }
}
