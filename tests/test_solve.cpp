#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/json.hpp"
#include "momentid/estimate.hpp"
#include "momentid/random.hpp"
#include "solve/distributions.hpp"

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

  TEST_CASE(
      "optimally weighted standard errors and J test are calibrated for weights from few "
      "batches") {
    // m = 30 equations b_r = mu_r in q = 2 parameters (a fixed), from B = 80 Gaussian batch
    // means with correlated components, repeated 1000 times. The weights come from the same 80
    // batches, so the uncorrected standard errors would be 1.55 times too small and the
    // chi-square J test would reject half of the time at the 5% level.
    constexpr std::size_t m = 30, batches = 80, repeats = 1000;
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
    int rejections = 0;
    for (std::size_t k = 0; k < repeats; ++k) {
      momentid::MomentEstimates estimates;
      estimates.mean.assign(m, 0.0);
      for (std::size_t b = 0; b < batches; ++b) {
        std::vector<double> z(m), mean(m);
        for (double& x : z) x = random.normal();
        for (std::size_t i = 0; i < m; ++i) {
          mean[i] = a[i][0] * theta[0] + a[i][1] * theta[1];
          for (std::size_t j = 0; j < m; ++j) mean[i] += mix[i][j] * z[j];
          estimates.mean[i] += mean[i] / batches;
        }
        estimates.batch_means.push_back(mean);
      }
      const momentid::Estimate e =
          momentid::solve_rows(rows, {"p", "q"}, estimates, estimates.covariance(), {.gmm = true});
      REQUIRE(e.gmm_parameters.size() == 2);
      for (std::size_t p = 0; p < 2; ++p) {
        squared_error[p] += std::pow(e.gmm_parameters[p].estimate - theta[p], 2) / repeats;
        variance[p] += std::pow(e.gmm_parameters[p].std_error, 2) / repeats;
      }
      REQUIRE(e.j_pvalue.has_value());
      rejections += *e.j_pvalue < 0.05;
    }
    // The ratio of mean squared error to mean variance has a relative standard error of about
    // sqrt(2 / 1000) = 4.5%; the rejection count is binomial(1000, 0.05), standard deviation 6.9.
    for (std::size_t p = 0; p < 2; ++p) {
      INFO("parameter ", p, ": squared error / reported variance ", squared_error[p] / variance[p]);
      CHECK(std::abs(squared_error[p] / variance[p] - 1) < 4 * 0.045);
    }
    INFO("J rejections at 5%: ", rejections);
    CHECK(std::abs(rejections - 50) < 4 * 6.9);
  }

  TEST_CASE("JSON strings escape quotes and control characters and stay valid UTF-8") {
    CHECK(momentid::json_string("a\"b\\c\nd\x01") == "\"a\\\"b\\\\c\\nd\\u0001\"");
    CHECK(momentid::json_string("\xc3\xa9t\xff") == "\"\xc3\xa9t\\ufffd\"");
  }
}
