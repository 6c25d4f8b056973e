// The channel sums of a pass (LagSums): taken a block at a time, or in shards merged in record
// order, they are the sums taken row by row, up to the order of the additions. The point sums
// are the means of every row of a short record, and of a thinning sample of a long one.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "common/bytes.hpp"
#include "momentid/error.hpp"
#include "moments/lag_sums.hpp"

namespace {

using momentid::ChannelStatistics;
using momentid::LagSums;
using momentid::Monomial;

constexpr std::size_t kChannels = 3, kLags = 6, kRows = 200;
// Two runs: rows [0, kSecondRun) and [kSecondRun, kRows).
constexpr std::size_t kSecondRun = 120;

// x0^2, x0 x2, x1 x2^2 and x0^2 again (a product that repeats), over the three channels.
const std::vector<Monomial> kPoints = {{2, 0, 0}, {1, 0, 1}, {0, 1, 2}, {2, 0, 0}};

// The mean of point monomial k over rows [begin, end).
double direct_mean(const std::vector<double>& rows, std::size_t k, std::size_t begin,
                   std::size_t end) {
  double sum = 0;
  for (std::size_t r = begin; r < end; ++r) {
    double p = 1;
    for (std::size_t c = 0; c < kChannels; ++c)
      p *= std::pow(rows[r * kChannels + c], kPoints[k][c]);
    sum += p;
  }
  return sum / static_cast<double>(end - begin);
}

// Rows about a large mean (the offset's case), with one outlier per channel.
std::vector<double> make_rows() {
  std::mt19937 random(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> rows(kRows * kChannels);
  for (std::size_t r = 0; r < kRows; ++r) {
    for (std::size_t c = 0; c < kChannels; ++c) rows[r * kChannels + c] = 100.0 * c + noise(random);
  }
  rows[37 * kChannels + 0] = 9.0;
  rows[150 * kChannels + 1] = -140.0;
  rows[kRows * kChannels - 1] = 260.0;
  return rows;
}

std::size_t run_start(std::size_t row) { return row < kSecondRun ? 0 : kSecondRun; }

// Adds rows [begin, end) as the pass does, in blocks of at most `block` rows that never span two
// runs; the run already started at `begin` unless it begins there.
void add_rows(LagSums& sums, const std::vector<double>& rows, std::size_t begin, std::size_t end,
              std::size_t block) {
  for (std::size_t r = begin; r < end;) {
    if (r == run_start(r)) sums.start_run();
    const std::size_t run_end = r < kSecondRun ? kSecondRun : kRows;
    const std::size_t count = std::min({block, end - r, run_end - r});
    sums.add(rows.data() + r * kChannels, count);
    r += count;
  }
}

// Rounding of sums of 200 values of order 1 (the offset taken off): far below 1e-12.
void check_same(const LagSums& got, const LagSums& want, std::size_t lags = kLags) {
  for (std::size_t c = 0; c < kChannels; ++c) {
    const ChannelStatistics g = got.statistics(c, false), w = want.statistics(c, false);
    CHECK(g.mean == doctest::Approx(w.mean).epsilon(1e-12));
    CHECK(g.variance == doctest::Approx(w.variance).epsilon(1e-12));
    REQUIRE(g.noise_variance);
    CHECK(*g.noise_variance == doctest::Approx(*w.noise_variance).epsilon(1e-12));
    CHECK(g.largest == w.largest);
    CHECK(g.largest_row == w.largest_row);
    REQUIRE(g.autocorrelation.size() == lags);
    for (std::size_t l = 0; l < lags; ++l) {
      CHECK(g.autocorrelation[l] == doctest::Approx(w.autocorrelation[l]).epsilon(1e-12));
    }
  }
}

}  // namespace

TEST_SUITE("lag sums") {
  // Blocks of at least twice the lags, past a run's first six rows, are taken in one sweep
  // (up to four lags); the others, and the rows one by one, by a kernel per sum.
  TEST_CASE("the lag sums over blocks of every size are those taken row by row") {
    const std::vector<double> rows = make_rows();
    for (const std::size_t lags : {std::size_t{1}, std::size_t{3}, std::size_t{4}, kLags}) {
      CAPTURE(lags);
      LagSums by_row(kChannels, lags);
      add_rows(by_row, rows, 0, kRows, 1);
      CHECK(by_row.statistics(0, false).largest_row == 37);
      CHECK(by_row.statistics(1, false).largest_row == 150);
      CHECK(by_row.statistics(2, false).largest_row == kRows - 1);
      for (std::size_t block = 2; block <= kRows; ++block) {
        CAPTURE(block);
        LagSums sums(kChannels, lags);
        add_rows(sums, rows, 0, kRows, block);
        check_same(sums, by_row, lags);
      }
    }
  }

  TEST_CASE("the lag sums of shards merged in record order are those of one pass") {
    const std::vector<double> rows = make_rows();
    LagSums whole(kChannels, kLags);
    add_rows(whole, rows, 0, kRows, 1);
    for (std::size_t cut = 1; cut < kRows; ++cut) {
      CAPTURE(cut);
      LagSums first(kChannels, kLags), second(kChannels, kLags);
      add_rows(first, rows, 0, cut, 7);
      // The second shard's history: the rows of its run before the cut, in blocks.
      second.start_run();
      for (std::size_t r = run_start(cut); r < cut; r += 5) {
        second.add_history(rows.data() + r * kChannels, std::min<std::size_t>(5, cut - r));
      }
      add_rows(second, rows, cut, kRows, 64);
      first.merge(second);
      check_same(first, whole);
    }
  }

  // An acceleration's band, 5-150 Hz at 2048 Hz (40 sinusoids of random phase), with white noise
  // of 4e-4 of its variance, and without: the sixth difference finds the noise within 3% (its
  // own sampling error is 0.8% on 10^5 rows), and on the noise-free channel less than a
  // thousandth of that (what the band puts in the difference, 1e-8 of its variance); the form for
  // held inputs (|s|^3) finds it 30% off or worse.
  TEST_CASE("the noise of a broad-band smooth channel, from its sixth difference") {
    constexpr std::size_t rows = 100000;
    const double pi = 3.141592653589793, fs = 2048, share = 4e-4;
    std::mt19937 random(5);
    std::uniform_real_distribution<double> phase(0, 2 * pi), frequency(5, 150);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::vector<double> signal(rows, 0.0), noisy(2 * rows);
    for (int k = 0; k < 40; ++k) {
      const double w = 2 * pi * frequency(random) / fs, p = phase(random);
      for (std::size_t r = 0; r < rows; ++r) signal[r] += std::sin(w * r + p);
    }
    double variance = 0, noise_variance = 0;
    for (double x : signal) variance += x * x / rows;
    for (std::size_t r = 0; r < rows; ++r) {
      const double e = std::sqrt(share * variance) * noise(random);
      noise_variance += e * e / rows;
      noisy[2 * r] = signal[r] + e;
      noisy[2 * r + 1] = signal[r];
    }
    LagSums sums(2, 4);
    sums.start_run();
    for (std::size_t r = 0; r < rows; r += 4096) {
      sums.add(noisy.data() + 2 * r, std::min<std::size_t>(4096, rows - r));
    }
    REQUIRE(sums.statistics(0, false).noise_variance);
    CHECK(*sums.statistics(0, false).noise_variance ==
          doctest::Approx(noise_variance).epsilon(0.03));
    CHECK(std::abs(*sums.statistics(0, true).noise_variance - noise_variance) >
          0.3 * noise_variance);
    CHECK(*sums.statistics(1, false).noise_variance < 1e-3 * noise_variance);
    // The rows the difference reaches back are kept whatever the lags.
    LagSums one_lag(2, 1);
    one_lag.start_run();
    one_lag.add(noisy.data(), rows);
    CHECK(*one_lag.statistics(0, false).noise_variance ==
          doctest::Approx(*sums.statistics(0, false).noise_variance).epsilon(1e-12));
  }

  TEST_CASE("the point sums of a short record are the means of every row, in any shards") {
    const std::vector<double> rows = make_rows();
    LagSums whole(kChannels, kLags, kPoints);
    add_rows(whole, rows, 0, kRows, 7);
    const std::vector<double> means = whole.point_means();
    REQUIRE(means.size() == kPoints.size());
    for (std::size_t k = 0; k < kPoints.size(); ++k) {
      CHECK(means[k] == doctest::Approx(direct_mean(rows, k, 0, kRows)).epsilon(1e-12));
    }
    CHECK(means[3] == means[0]);
    // Two shards, the second through the bytes another process would send.
    LagSums first(kChannels, kLags, kPoints), second(kChannels, kLags, kPoints);
    add_rows(first, rows, 0, 90, 16);
    second.start_run();
    add_rows(second, rows, 90, kRows, 16);
    momentid::ByteWriter out;
    second.save(out);
    const std::vector<std::uint8_t> bytes = out.take();
    momentid::ByteReader in(bytes, "the test's bytes");
    first.merge(LagSums::load(in, kChannels, kLags));
    const std::vector<double> merged = first.point_means();
    for (std::size_t k = 0; k < kPoints.size(); ++k) {
      CHECK(merged[k] == doctest::Approx(means[k]).epsilon(1e-12));
    }
    // Sums of other monomials do not merge.
    LagSums other(kChannels, kLags, {{1, 0, 0}});
    add_rows(other, rows, 0, kRows, 50);
    CHECK_THROWS_AS(first.merge(other), momentid::Error);
  }

  TEST_CASE("a long shard's point sums thin out, each row sampled standing for those it skips") {
    // Channel 0 white noise, channel 1 a ramp, channel 2 constant: the ramp's weighted mean is
    // its mean up to half the largest stride, the constant's exact, the square's within four
    // standard errors of the weighted sample (every row of the first 2^12, every 2nd to 2^13,
    // ..., every 32nd from 2^16 on).
    constexpr std::size_t kLong = 400000;
    std::mt19937 random(5);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::vector<double> rows(kLong * kChannels);
    for (std::size_t r = 0; r < kLong; ++r) {
      rows[r * kChannels] = noise(random);
      rows[r * kChannels + 1] = static_cast<double>(r) / kLong;
      rows[r * kChannels + 2] = 3.0;
    }
    LagSums sums(kChannels, 1, {{2, 0, 0}, {0, 1, 0}, {0, 0, 1}});
    sums.start_run();
    for (std::size_t r = 0; r < kLong; r += 1000) sums.add(rows.data() + r * kChannels, 1000);
    const std::vector<double> means = sums.point_means();
    double square = 0;
    for (std::size_t r = 0; r < kLong; ++r) square += rows[r * kChannels] * rows[r * kChannels];
    square /= kLong;
    // The weights: 1 for the first 2^12 rows, then stride s over [2^12 s / 2, 2^12 s): the sum
    // of their squares.
    double weights_squared = 4096;
    for (std::size_t stride = 2, end = 8192; stride <= 32; stride *= 2, end *= 2) {
      const std::size_t last = stride == 32 ? kLong : end;
      weights_squared += static_cast<double>((last - end / 2) / stride) * stride * stride;
    }
    const double error = std::sqrt(2 * weights_squared) / kLong;  // Var(x^2) = 2
    CHECK(error < 0.02);
    CHECK(std::abs(means[0] - square) < 4 * error);
    CHECK(means[1] == doctest::Approx(0.5).epsilon(32.0 / kLong));
    CHECK(means[2] == doctest::Approx(3.0).epsilon(1e-15));
  }
}
