// The statistics validate compares for a model whose trajectory cannot be reproduced: Welch
// spectra, quantiles, up-crossing rates and the white-noise estimate, on signals whose values
// are known.

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "app/validate/series_statistics.hpp"

namespace momentid {
namespace {

std::vector<double> sine(double amplitude, double frequency, double dt, std::size_t n) {
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = amplitude * std::sin(2 * std::numbers::pi * frequency * static_cast<double>(i) * dt);
  }
  return out;
}

std::vector<double> white(double sd, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0.0, sd);
  std::vector<double> out(n);
  for (double& x : out) x = noise(random);
  return out;
}

}  // namespace

TEST_SUITE("validate statistics") {
  TEST_CASE("the Welch density of white noise of variance s2 is 2 s2 dt at every frequency") {
    const double dt = 0.01, sd = 3;
    const std::size_t segment = 256;
    const std::vector<double> psd = welch_psd({white(sd, 200000, 1)}, dt, segment);
    REQUIRE(psd.size() == segment / 2 + 1);
    // Bin 1 is left out: each segment's mean is removed before the window, and the window
    // spreads that removal into bin 1. The average over the other 126 interior bins of about
    // 1560 half-overlapping segments: each bin has a relative standard error of about
    // 1.03/sqrt(1560) (Hann, half overlap), their mean about 1/sqrt(126) of that; 5 standard
    // errors.
    const double want = 2 * sd * sd * dt, error = 1.03 / std::sqrt(1560.0);
    double mean = 0;
    for (std::size_t k = 2; k < segment / 2; ++k) {
      mean += psd[k] / (segment / 2 - 2);
      CHECK(std::abs(psd[k] / want - 1) < 5 * error);
    }
    CHECK(std::abs(mean / want - 1) < 5 * error / std::sqrt(126.0));
  }

  TEST_CASE("the Welch density of a sine holds its mean square A^2/2 at its frequency") {
    const double dt = 0.001, amplitude = 2;
    const std::size_t segment = 1024;
    const std::vector<double> f = psd_frequencies(dt, segment);
    const double frequency = f[100];  // on a bin: the Hann window spreads it over three
    const std::vector<double> psd = welch_psd({sine(amplitude, frequency, dt, 50000)}, dt, segment);
    double power = 0;
    for (double p : psd) power += p * (f[1] - f[0]);
    // Exact up to rounding: the periodic Hann window's three bins hold all of a bin sine's power.
    CHECK(power == doctest::Approx(amplitude * amplitude / 2).epsilon(1e-9));
    // The Hann window's neighbours hold half the amplitude, a quarter of the density.
    CHECK(psd[99] == doctest::Approx(psd[100] / 4).epsilon(1e-9));
    CHECK(psd[101] == doctest::Approx(psd[100] / 4).epsilon(1e-9));
    CHECK(psd[103] < 1e-12 * psd[100]);
  }

  TEST_CASE("a run shorter than a segment adds nothing to the Welch density") {
    const std::vector<double> psd =
        welch_psd({sine(1, 5, 0.01, 1000), std::vector<double>(100, 7.0)}, 0.01, 256);
    const std::vector<double> alone = welch_psd({sine(1, 5, 0.01, 1000)}, 0.01, 256);
    CHECK(psd == alone);
  }

  TEST_CASE("quantiles interpolate between order statistics as numpy's default") {
    std::vector<double> values;
    for (int i = 100; i >= 0; --i) values.push_back(i);
    const std::vector<double> q = quantiles({values}, {0, 0.255, 0.5, 1});
    CHECK(q[0] == 0);
    CHECK(q[1] == doctest::Approx(25.5));
    CHECK(q[2] == 50);
    CHECK(q[3] == 100);
    // Two runs pool their values.
    CHECK(quantiles({{1, 2}, {3, 4}}, {0.5})[0] == doctest::Approx(2.5));
  }

  TEST_CASE("a sine of frequency f crosses each level inside its amplitude f times a second") {
    const double dt = 0.001, frequency = 3.125;  // 320 samples per period, 200 periods
    const std::vector<double> x = sine(1, frequency, dt, 64000);
    const std::vector<double> rates = upcrossing_rates({x}, dt, {-0.5, 0, 0.9, 1.5}, 0);
    // The first period's crossing of -0.5 and 0 needs a value below them first: 199 of 200
    // crossings of 0 (the sine starts at 0), 200 of -0.5 and 0.9.
    CHECK(rates[0] == doctest::Approx(200 / 64.0));
    CHECK(rates[1] == doctest::Approx(199 / 64.0));
    CHECK(rates[2] == doctest::Approx(200 / 64.0));
    CHECK(rates[3] == 0);
  }

  TEST_CASE("the hysteresis keeps noise around a level from counting as crossings") {
    const double dt = 0.001;
    std::vector<double> x = sine(1, 3.125, dt, 64000);
    // Noise of 0.05 against a slope of 0.02 per sample chatters around each level.
    const std::vector<double> noise = white(0.05, x.size(), 2);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] += noise[i];
    CHECK(upcrossing_rates({x}, dt, {0}, 0)[0] > 1.5 * 199 / 64.0);
    // Three noise standard deviations of hysteresis: 200 crossings, the first included now
    // that the noise takes the start below -0.15 within the first quarter period.
    const double rate = upcrossing_rates({x}, dt, {0}, 0.15)[0];
    CHECK((rate == doctest::Approx(199 / 64.0) || rate == doctest::Approx(200 / 64.0)));
  }

  TEST_CASE("the white noise on a smooth signal is estimated from its autocorrelation") {
    const double dt = 0.001, sd = 0.02;
    std::vector<double> x = sine(1, 3.125, dt, 64000);
    const std::vector<double> noise = white(sd, x.size(), 3);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] += noise[i];
    // The lag-1..4 autocovariances of 64000 samples each carry a standard error of about
    // sd^2 / sqrt(64000) = 1.6e-6, which the extrapolation multiplies by about 1.8: 7 times
    // that is 2e-5 against a variance of 4e-4.
    CHECK(std::abs(white_noise_variance({x}, false) - sd * sd) < 2e-5);
    CHECK(white_noise_variance({sine(1, 3.125, dt, 64000)}, false) < 1e-9);
  }
}

}  // namespace momentid
