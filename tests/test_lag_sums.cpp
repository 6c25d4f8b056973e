// The channel sums of a pass (LagSums): taken a block at a time, or in shards merged in record
// order, they are the sums taken row by row, up to the order of the additions.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "moments/lag_sums.hpp"

namespace {

using momentid::ChannelStatistics;
using momentid::LagSums;

constexpr std::size_t kChannels = 3, kLags = 4, kRows = 200;
// Two runs: rows [0, kSecondRun) and [kSecondRun, kRows).
constexpr std::size_t kSecondRun = 120;

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
void check_same(const LagSums& got, const LagSums& want) {
  for (std::size_t c = 0; c < kChannels; ++c) {
    const ChannelStatistics g = got.statistics(c, false), w = want.statistics(c, false);
    CHECK(g.mean == doctest::Approx(w.mean).epsilon(1e-12));
    CHECK(g.variance == doctest::Approx(w.variance).epsilon(1e-12));
    CHECK(g.largest == w.largest);
    CHECK(g.largest_row == w.largest_row);
    REQUIRE(g.autocorrelation.size() == kLags);
    for (std::size_t l = 0; l < kLags; ++l) {
      CHECK(g.autocorrelation[l] == doctest::Approx(w.autocorrelation[l]).epsilon(1e-12));
    }
  }
}

}  // namespace

TEST_SUITE("lag sums") {
  TEST_CASE("the lag sums over blocks of every size are those taken row by row") {
    const std::vector<double> rows = make_rows();
    LagSums by_row(kChannels, kLags);
    add_rows(by_row, rows, 0, kRows, 1);
    CHECK(by_row.statistics(0, false).largest_row == 37);
    CHECK(by_row.statistics(1, false).largest_row == 150);
    CHECK(by_row.statistics(2, false).largest_row == kRows - 1);
    for (std::size_t block = 2; block <= kRows; ++block) {
      CAPTURE(block);
      LagSums sums(kChannels, kLags);
      add_rows(sums, rows, 0, kRows, block);
      check_same(sums, by_row);
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
}
