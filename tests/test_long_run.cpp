#include <doctest/doctest.h>

#include <cmath>
#include <functional>

#include "momentid/random.hpp"
#include "solve/long_run.hpp"

namespace {

// A batch series of `batches` rows: `white` times independent normals plus `boundary` times the
// difference of independent normals at the batches' ends (what the moment conditions of a
// record without noise look like: their sums telescope), in two columns mixed by a fixed matrix.
Eigen::MatrixXd series(momentid::PortableRandom& random, Eigen::Index batches, double white,
                       double boundary) {
  Eigen::MatrixXd ends(batches + 1, 2), out(batches, 2);
  for (Eigen::Index b = 0; b <= batches; ++b) {
    ends(b, 0) = random.normal();
    ends(b, 1) = random.normal();
  }
  Eigen::Matrix2d mix;
  mix << 1, 0.5, -0.3, 2;
  for (Eigen::Index b = 0; b < batches; ++b) {
    const Eigen::Vector2d noise(random.normal(), random.normal());
    out.row(b) = (mix * (white * noise + boundary * (ends.row(b + 1) - ends.row(b)).transpose()))
                     .transpose();
  }
  return out;
}

struct Calibration {
  double variance_ratio[2] = {0, 0};  // mean reported variance / variance of the mean
  int covered[2] = {0, 0};            // 95% t intervals that contain the true mean, 0
  double mean_dof = 0;
};

// `repeats` series; their true mean is zero.
Calibration calibrate(Eigen::Index batches, double white, double boundary, int repeats) {
  momentid::PortableRandom random(11, 0);
  Calibration out;
  double reported[2] = {0, 0}, squares[2] = {0, 0};
  for (int r = 0; r < repeats; ++r) {
    const Eigen::MatrixXd x = series(random, batches, white, boundary);
    const Eigen::RowVector2d mean = x.colwise().mean();
    const momentid::LongRunCovariance c = momentid::long_run_covariance(x);
    const double t = c.t975();
    for (int k = 0; k < 2; ++k) {
      reported[k] += c.covariance(k, k);
      squares[k] += mean(k) * mean(k);
      out.covered[k] += std::abs(mean(k)) <= t * std::sqrt(c.covariance(k, k));
    }
    out.mean_dof += c.dof / repeats;
  }
  for (int k = 0; k < 2; ++k) out.variance_ratio[k] = reported[k] / squares[k];
  return out;
}

// Over 1000 repeats: the ratio of mean reported variance to the mean square of the mean has a
// relative standard error of about sqrt(2 / 1000) = 4.5% (the reported variances vary less than
// the squares); coverage is binomial(1000, 0.95), standard deviation 6.9.
void check(const Calibration& c) {
  for (int k = 0; k < 2; ++k) {
    INFO("column ", k, ": reported / true variance ", c.variance_ratio[k], ", covered ",
         c.covered[k], " of 1000, mean dof ", c.mean_dof);
    CHECK(std::abs(c.variance_ratio[k] - 1) < 4 * 0.045);
    CHECK(std::abs(c.covered[k] - 950) < 4 * 6.9);
  }
}

}  // namespace

TEST_SUITE("long-run covariance") {
  TEST_CASE("independent batch means: the covariance of their mean") {
    check(calibrate(400, 1, 0, 1000));
  }

  TEST_CASE("telescoping batch means: 2 Var(end) / B^2, not the batch covariance's 2 / B") {
    check(calibrate(400, 0, 1, 1000));
    // The batch covariance S / B is about B / 2 = 200 times the variance of the mean.
    momentid::PortableRandom random(3, 0);
    const Eigen::MatrixXd x = series(random, 400, 0, 1);
    const double ratio =
        momentid::batch_covariance(x)(0, 0) / momentid::long_run_covariance(x).covariance(0, 0);
    CHECK(ratio > 100);
  }

  TEST_CASE("both at once, the white part dominating the mean at this batch count") {
    // White variance 0.05^2 / B against telescoping 2 / B^2: equal at B = 800.
    check(calibrate(400, 0.05, 1, 1000));
  }

  TEST_CASE("the same answer whatever the batch count") {
    // Batches merged by 2 and by 4 from the same 1600: the mean variance of the mean stays
    // (the batch covariance would change by the factor). A record's variance has a relative
    // standard deviation near sqrt(2 / dof) = 0.35 (dof near 16); over 200 records a mean has
    // 0.025, a ratio of two at most 0.035: four of those.
    for (const auto& [white_level, boundary_level] : {std::pair{1.0, 0.0}, std::pair{0.0, 1.0}}) {
      const double white = white_level, boundary = boundary_level;  // for INFO (no bindings)
      double sum[3] = {0, 0, 0};
      momentid::PortableRandom random(5, 0);
      for (int r = 0; r < 200; ++r) {
        const Eigen::MatrixXd x = series(random, 1600, white, boundary);
        for (int i = 0; i < 3; ++i) {
          const Eigen::Index f = Eigen::Index{1} << i;
          Eigen::MatrixXd merged(x.rows() / f, 2);
          for (Eigen::Index b = 0; b < merged.rows(); ++b) {
            merged.row(b) = x.middleRows(b * f, f).colwise().mean();
          }
          sum[i] += momentid::long_run_covariance(merged).covariance(0, 0);
        }
      }
      INFO("white ", white, ", boundary ", boundary, ": halved ", sum[1] / sum[0], ", quartered ",
           sum[2] / sum[0]);
      CHECK(std::abs(sum[1] / sum[0] - 1) < 4 * 0.035);
      CHECK(std::abs(sum[2] / sum[0] - 1) < 4 * 0.035);
    }
  }

  TEST_CASE("few batches: their covariance, as if independent") {
    momentid::PortableRandom random(9, 0);
    const Eigen::MatrixXd x = series(random, 12, 1, 0);
    const momentid::LongRunCovariance c = momentid::long_run_covariance(x);
    CHECK(c.order == 0);
    CHECK(c.dof == 11);
    CHECK(c.covariance.isApprox(momentid::batch_covariance(x)));
  }

  // The J test's traces (j_test.cpp): over many directions of almost no long-run variance, the
  // zeroed negative eigenvalues leave a positive part of the noise in each.
  TEST_CASE("the linear estimate's trace is unbiased where the zeroed one is not") {
    momentid::PortableRandom random(13, 0);
    constexpr Eigen::Index kBatches = 500, kWhite = 4, kColumns = 40;
    constexpr int kRepeats = 200;
    // The mean's covariance times B: 1 per white column, 2 / B per telescoping one.
    const double truth = kWhite + 2.0 * (kColumns - kWhite) / kBatches;
    double sum[2] = {0, 0}, squares[2] = {0, 0};
    for (int r = 0; r < kRepeats; ++r) {
      Eigen::MatrixXd x(kBatches, kColumns);
      for (Eigen::Index c = 0; c < kColumns; ++c) {
        double end = random.normal();
        for (Eigen::Index b = 0; b < kBatches; ++b) {
          const double next = random.normal();
          x(b, c) = c < kWhite ? next : next - end;
          end = next;
        }
      }
      const momentid::LongRunCovariance c = momentid::long_run_covariance(x);
      const double traces[2] = {c.linear.trace() * kBatches, c.covariance.trace() * kBatches};
      for (int k = 0; k < 2; ++k) {
        sum[k] += traces[k];
        squares[k] += traces[k] * traces[k];
      }
    }
    double mean[2], error[2];
    for (int k = 0; k < 2; ++k) {
      mean[k] = sum[k] / kRepeats;
      error[k] = std::sqrt((squares[k] / kRepeats - mean[k] * mean[k]) / (kRepeats - 1));
    }
    INFO("linear " << mean[0] << " +- " << error[0] << ", zeroed " << mean[1] << " +- " << error[1]
                   << ", truth " << truth);
    CHECK(std::abs(mean[0] - truth) < 4 * error[0]);
    CHECK(mean[1] - truth > 4 * error[1]);
  }

  TEST_CASE("grouped: the covariance of the mean of the groups' means") {
    Eigen::MatrixXd x(6, 1);
    x << 1, 3, 5, 7, 2, 4;  // group means 2, 6, 3 about 11/3
    const double expected =
        (std::pow(2 - 11.0 / 3, 2) + std::pow(6 - 11.0 / 3, 2) + std::pow(3 - 11.0 / 3, 2)) /
        (3 * 2);
    CHECK(momentid::grouped_covariance(x, 3)(0, 0) == doctest::Approx(expected).epsilon(1e-14));
  }

  TEST_CASE("grouped: one extreme batch near an end counts in full, where the taper hides it") {
    // White batch means with one batch 30 standard deviations out at 92% of the record: it holds
    // two thirds of the variance, which the Hann taper there weighs by about 0.05.
    momentid::PortableRandom random(5, 0);
    Eigen::MatrixXd x(498, 1);
    for (Eigen::Index b = 0; b < x.rows(); ++b) x(b, 0) = random.normal();
    x(460, 0) = 30;
    const double grouped = momentid::grouped_covariance(x, 50)(0, 0);
    const double naive = momentid::batch_covariance(x)(0, 0);
    const double spectral = momentid::long_run_covariance(x).covariance(0, 0);
    INFO("grouped ", grouped, ", independent batches ", naive, ", spectral ", spectral);
    CHECK(std::abs(grouped / naive - 1) < 0.5);
    CHECK(grouped > 2 * spectral);
  }

  TEST_CASE("constant columns have no error") {
    const momentid::LongRunCovariance c =
        momentid::long_run_covariance(Eigen::MatrixXd::Ones(100, 3));
    CHECK(c.covariance.isZero());
  }
}
