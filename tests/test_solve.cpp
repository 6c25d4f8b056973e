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
      REQUIRE(e.gmm_parameters.size() == 2);
      for (std::size_t p = 0; p < 2; ++p) {
        squared_error[p] += std::pow(e.gmm_parameters[p].estimate - theta[p], 2) / repeats;
        variance[p] += std::pow(e.gmm_parameters[p].std_error, 2) / repeats;
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
}
