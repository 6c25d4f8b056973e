// The moment accumulator as a value: shards of a record accumulated apart, serialised and merged
// give the moments of one pass; the Moment key's normal form; the errors of bad bytes and bad
// merges, verbatim.

#include <doctest/doctest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "momentid/accumulator.hpp"
#include "momentid/data_pass.hpp"
#include "momentid/moment.hpp"
#include "momentid/random.hpp"
#include "moments/integration.hpp"
#include "test_support.hpp"

namespace {

using momentid::InputHold;
using momentid::Moment;
using momentid::MomentAccumulator;
using momentid::MomentFactor;
using momentid::testing::error_from;

constexpr std::size_t kStates = 2, kInputs = 1, kChannels = kStates + kInputs;
constexpr std::size_t kBatches = 4;

// Runs of one record, as rows of y1, y2 (states) and x (input), row-major.
struct Record {
  std::vector<double> values;
  std::vector<std::size_t> run_starts;  // the first row of each run, from 0

  std::size_t rows() const { return values.size() / kChannels; }
  const double* row(std::size_t r) const { return values.data() + r * kChannels; }
  bool starts_run(std::size_t r) const {
    return std::binary_search(run_starts.begin(), run_starts.end(), r);
  }
  // One past the last row of the run that holds row r.
  std::size_t run_end(std::size_t r) const {
    const auto next = std::upper_bound(run_starts.begin(), run_starts.end(), r);
    return next == run_starts.end() ? rows() : *next;
  }
  // The first row of each interval, in order, from the largest lag `lag` of each run on.
  std::vector<std::size_t> interval_rows(std::size_t lag) const {
    std::vector<std::size_t> out;
    for (std::size_t begin : run_starts) {
      for (std::size_t n = begin + lag; n + 1 < run_end(begin); ++n) out.push_back(n);
    }
    return out;
  }
  // The product of `moment` at `row`, its most lagged factor read `lag` (the largest lag among
  // the accumulator's moments) rows back, as the accumulator reads it.
  double product(const Moment& moment, std::size_t row, std::size_t lag) const {
    double out = 1;
    const std::size_t shift = lag - static_cast<std::size_t>(moment.max_lag());
    for (const MomentFactor& f : moment.factors()) {
      out *= std::pow(this->row(row - shift - static_cast<std::size_t>(f.lag))[f.channel], f.power);
    }
    return out;
  }
};

// Smooth channels, sums of sines with fixed phases, plus a little noise; offset from 0 so that
// every moment is well away from 0 and a relative tolerance is meaningful.
Record make_record(const std::vector<std::size_t>& run_lengths) {
  momentid::PortableRandom random(/*seed=*/7, /*stream=*/0);
  Record record;
  for (std::size_t length : run_lengths) {
    record.run_starts.push_back(record.rows());
    for (std::size_t i = 0; i < length; ++i) {
      const double t = 0.05 * static_cast<double>(record.rows());
      record.values.push_back(2.0 + std::sin(1.3 * t + 0.4) + 0.3 * std::sin(3.1 * t + 1.0) +
                              0.01 * random.normal());
      record.values.push_back(1.5 + std::cos(0.7 * t + 2.0) + 0.2 * std::sin(5.3 * t) +
                              0.01 * random.normal());
      record.values.push_back(1.0 + 0.5 * std::sin(2.3 * t + 0.9) + 0.01 * random.normal());
    }
  }
  return record;
}

// Every moment of degree 0 to 3 in y1, y2, x.
std::vector<Moment> all_moments() {
  std::vector<Moment> out;
  for (int a = 0; a <= 3; ++a) {
    for (int b = 0; a + b <= 3; ++b) {
      for (int c = 0; a + b + c <= 3; ++c) out.push_back(Moment::from_monomial({a, b, c}));
    }
  }
  return out;
}

// Moments with factors up to 5 rows back, of states and the input.
std::vector<Moment> lagged_moments() {
  return {Moment::from_monomial({1, 0, 0}), Moment({{0, 1, 3}, {1, 1, 0}}),
          Moment({{0, 1, 0}, {2, 1, 2}}),   Moment({{0, 3, 5}, {0, 1, 0}}),
          Moment({{1, 2, 1}, {2, 1, 4}}),   Moment({{2, 1, 5}, {0, 1, 0}, {1, 1, 2}})};
}

MomentAccumulator one_pass(const Record& record, InputHold hold,
                           const std::vector<Moment>& moments = all_moments()) {
  MomentAccumulator acc(moments, kStates, kInputs, hold, kBatches);
  for (std::size_t begin : record.run_starts) {
    acc.start_run();
    acc.add(record.row(begin), record.run_end(begin) - begin);
  }
  acc.finish();
  return acc;
}

// Rows [begin, end) of the record as one shard: a shard may hold the end of one run and the
// start of the next, and takes the lookahead rows of the run it ends in.
MomentAccumulator shard(const Record& record, std::size_t begin, std::size_t end, InputHold hold,
                        const std::vector<Moment>& moments) {
  MomentAccumulator acc(moments, kStates, kInputs, hold, kBatches);
  if (record.starts_run(begin)) {
    acc.start_run();
  } else {
    acc.continue_run();
    // The rows of the run before the shard that its lagged factors reach.
    std::size_t run_start = begin;
    while (!record.starts_run(run_start)) --run_start;
    const std::size_t history = std::min(acc.max_lag(), begin - run_start);
    if (history > 0) acc.add_history(record.row(begin - history), history);
  }
  for (std::size_t r = begin; r < end;) {
    if (r > begin && record.starts_run(r)) acc.start_run();
    const std::size_t stop = std::min(end, record.run_end(r));
    acc.add(record.row(r), stop - r);
    r = stop;
  }
  const std::size_t after =
      std::min(record.run_end(end - 1), end + MomentAccumulator::kLookaheadRows);
  if (after > end) acc.add_lookahead(record.row(end), after - end);
  acc.finish();
  return acc;
}

// The shards between consecutive cuts (0 and the record's end included), each sent through
// serialize and deserialize, merged in record order.
MomentAccumulator merged_shards(const Record& record, std::vector<std::size_t> cuts, InputHold hold,
                                const std::vector<Moment>& moments = all_moments()) {
  cuts.insert(cuts.begin(), 0);
  cuts.push_back(record.rows());
  MomentAccumulator whole =
      MomentAccumulator::deserialize(shard(record, cuts[0], cuts[1], hold, moments).serialize());
  for (std::size_t i = 1; i + 1 < cuts.size(); ++i) {
    whole.merge(MomentAccumulator::deserialize(
        shard(record, cuts[i], cuts[i + 1], hold, moments).serialize()));
  }
  return whole;
}

// `count` distinct cut rows in 1 .. rows - 1, sorted.
std::vector<std::size_t> random_cuts(momentid::PortableRandom& random, std::size_t rows,
                                     std::size_t count) {
  std::set<std::size_t> cuts;
  while (cuts.size() < count) {
    cuts.insert(1 + static_cast<std::size_t>(random.uniform() * static_cast<double>(rows - 1)));
  }
  return {cuts.begin(), cuts.end()};
}

// One pass over the record (shards == 1), or that many shards cut at random rows and merged.
MomentAccumulator accumulate(const Record& record, std::size_t shards,
                             momentid::PortableRandom& random, InputHold hold,
                             const std::vector<Moment>& moments) {
  if (shards == 1) return one_pass(record, hold, moments);
  return merged_shards(record, random_cuts(random, record.rows(), shards - 1), hold, moments);
}

void check_same_moments(const MomentAccumulator& got, const MomentAccumulator& want) {
  CHECK(got.intervals() == want.intervals());
  const auto g = momentid::estimates(got, kBatches).mean;
  const auto w = momentid::estimates(want, kBatches).mean;
  REQUIRE(g.size() == w.size());
  for (std::size_t i = 0; i < g.size(); ++i) {
    // The shards add the same interval averages in another order: a few hundred roundings of
    // 1e-16 each, far below 1e-12.
    INFO("moment ", momentid::to_string(got.moments()[i]), ": ", g[i], " vs ", w[i]);
    CHECK(std::abs(g[i] - w[i]) <= 1e-12 * std::abs(w[i]));
  }
}

// Walks the stretches of `acc` in record order, `first_rows[q]` being the first row of its q-th
// interval, and checks the sum of each moment in `checked` (positions in acc.moments()) over a
// stretch against the sum of interval_value(moment, n) over the stretch's intervals n, within
// tolerance(that sum).
template <class Value, class Tolerance>
void check_stretch_sums(const MomentAccumulator& acc, const std::vector<std::size_t>& first_rows,
                        const std::vector<std::size_t>& checked, Value interval_value,
                        Tolerance tolerance) {
  REQUIRE(acc.intervals() == first_rows.size());
  std::size_t next = 0;
  for (const MomentAccumulator::Stretch& stretch : acc.stretches()) {
    for (const std::size_t i : checked) {
      double want = 0;
      for (std::size_t q = next; q < next + stretch.intervals; ++q) {
        want += interval_value(acc.moments()[i], first_rows[q]);
      }
      INFO("stretch from interval ", next, ", ", to_string(acc.moments()[i]));
      CHECK(std::abs(stretch.sums[i] - want) <= tolerance(want));
    }
    next += stretch.intervals;
  }
  CHECK(next == first_rows.size());
}

// A tiny accumulator with a fixed layout: one state, the moment c0, three rows (two intervals,
// each closing a stretch of length 1), 138 bytes.
std::vector<std::uint8_t> tiny_bytes() {
  MomentAccumulator acc({Moment::from_monomial({1})}, 1, 0, InputHold::kSample, 1);
  const double rows[] = {1, 2, 3};
  acc.add(rows, 3);
  acc.finish();
  return acc.serialize();
}

std::string deserialize_error(const std::vector<std::uint8_t>& bytes) {
  return error_from<momentid::Error>([&] { MomentAccumulator::deserialize(bytes); }).what();
}

}  // namespace

TEST_SUITE("accumulator") {
  TEST_CASE("shards split at any rows, serialised and merged, give the one-pass moments") {
    // Runs of 1, 2 and 3 rows between longer ones; shards that end and start runs.
    const Record record = make_record({40, 1, 2, 3, 57, 4, 1, 96, 3, 2, 31});
    momentid::PortableRandom random(/*seed=*/11, /*stream=*/0);
    for (InputHold hold : {InputHold::kSample, InputHold::kZeroOrderHold}) {
      const MomentAccumulator want = one_pass(record, hold);
      for (std::size_t shards : {2, 3, 7}) {
        for (int trial = 0; trial < 20; ++trial) {
          const auto cuts = random_cuts(random, record.rows(), shards - 1);
          INFO("hold ", static_cast<int>(hold), ", ", shards, " shards, trial ", trial);
          check_same_moments(merged_shards(record, cuts, hold), want);
        }
      }
    }
  }

  TEST_CASE("shards of one row each, and shards cut at every run start, give one pass") {
    const Record record = make_record({5, 1, 2, 3, 9, 4});
    std::vector<std::size_t> every_row;
    for (std::size_t r = 1; r < record.rows(); ++r) every_row.push_back(r);
    const std::vector<std::size_t> run_starts(record.run_starts.begin() + 1,
                                              record.run_starts.end());
    for (InputHold hold : {InputHold::kSample, InputHold::kZeroOrderHold}) {
      const MomentAccumulator want = one_pass(record, hold);
      check_same_moments(merged_shards(record, every_row, hold), want);
      check_same_moments(merged_shards(record, run_starts, hold), want);
    }
  }

  // 2048 moments (y at lags 0 .. 2047 times y) and 300 intervals of one stretch each: the
  // blocks of slots grow by 16, 16, 32, 64, 128 and 256 stretches of 16 KiB, the last two of
  // 2 MiB or more, advised as large pages (the kernel's flag `hg` on their mapping); the open
  // stretch, the 301st, lies in the last.
  TEST_CASE("the stretches of a long pass lie in memory advised as large pages") {
    if (!std::filesystem::exists("/sys/kernel/mm/transparent_hugepage/enabled")) {
      MESSAGE("this kernel has no transparent huge pages: not checked");
      return;
    }
    std::vector<Moment> moments{Moment::from_monomial({2})};
    for (int lag = 1; lag < 2048; ++lag) moments.push_back(Moment({{0, 1, 0}, {0, 1, lag}}));
    MomentAccumulator acc(moments, 1, 0, InputHold::kSample, 100);
    momentid::PortableRandom random(/*seed=*/3, /*stream=*/0);
    std::vector<double> rows(2047 + 301);
    for (double& x : rows) x = random.normal();
    acc.add(rows.data(), rows.size());
    acc.finish();
    const std::vector<MomentAccumulator::Stretch> stretches = acc.stretches();
    REQUIRE(stretches.size() > 256);
    const auto address = reinterpret_cast<std::uintptr_t>(stretches.back().sums.data());
    std::ifstream smaps("/proc/self/smaps");
    bool inside = false;
    std::string flags;
    for (std::string line; std::getline(smaps, line);) {
      std::uintptr_t begin = 0, end = 0;
      char dash = 0;
      // A mapping's first line: "begin-end perms ...", in lower-case hexadecimal.
      if (std::isxdigit(static_cast<unsigned char>(line[0])) && !std::isupper(line[0])) {
        std::istringstream(line) >> std::hex >> begin >> dash >> end;
        inside = dash == '-' && begin <= address && address < end;
      } else if (inside && line.rfind("VmFlags:", 0) == 0) {
        flags = line + " ";
      }
    }
    INFO("the mapping's flags: ", flags);
    CHECK(flags.find(" hg ") != std::string::npos);
  }

  TEST_CASE("a serialised accumulator deserialises to the same stretches, bit for bit") {
    const Record record = make_record({300, 2, 77});
    const MomentAccumulator acc = one_pass(record, InputHold::kZeroOrderHold);
    const MomentAccumulator copy = MomentAccumulator::deserialize(acc.serialize());
    CHECK(copy.moments() == acc.moments());
    CHECK(copy.intervals() == acc.intervals());
    REQUIRE(copy.stretches().size() == acc.stretches().size());
    for (std::size_t i = 0; i < acc.stretches().size(); ++i) {
      CHECK(copy.stretches()[i].intervals == acc.stretches()[i].intervals);
      CHECK(std::ranges::equal(copy.stretches()[i].sums, acc.stretches()[i].sums));
    }
    CHECK(copy.serialize() == acc.serialize());
  }

  TEST_CASE("the trapezoidal rule for held products: u[n] (g[n] + g[n+1]) / 2, kept in its bytes") {
    // y = 1, 2, 4, 7 under x = 1 held: the cubic rule gives (17/12 + 70/24 + 65/12) / 3 = 3.25
    // (one-sided at the run's ends), the trapezoidal rule (1.5 + 3 + 5.5) / 3.
    const double rows[] = {1, 1, 2, 1, 4, 1, 7, 1};
    const auto mean = [&](momentid::HeldRule rule) {
      MomentAccumulator acc({Moment::from_monomial({1, 1})}, 1, 1, InputHold::kZeroOrderHold, 1,
                            rule);
      acc.add(rows, 4);
      acc.finish();
      const MomentAccumulator copy = MomentAccumulator::deserialize(acc.serialize());
      CHECK(copy.serialize() == acc.serialize());
      CHECK(acc.serialize()[28] == (rule == momentid::HeldRule::kCubic ? 1 : 2));
      return momentid::estimates(copy, 1).mean[0];
    };
    CHECK(mean(momentid::HeldRule::kCubic) == doctest::Approx(3.25).epsilon(1e-15));
    CHECK(mean(momentid::HeldRule::kTrapezoidal) == doctest::Approx(10.0 / 3).epsilon(1e-15));
    MomentAccumulator cubic({Moment::from_monomial({1, 1})}, 1, 1, InputHold::kZeroOrderHold, 1);
    const MomentAccumulator trapezoidal({Moment::from_monomial({1, 1})}, 1, 1,
                                        InputHold::kZeroOrderHold, 1,
                                        momentid::HeldRule::kTrapezoidal);
    CHECK(error_from<momentid::Error>([&] { cubic.merge(trapezoidal); }).what() ==
          std::string("cannot merge moment accumulators with different input holds: zero-order "
                      "hold here, zero-order hold (trapezoidal) in the other"));
  }

  TEST_CASE("a moment is normalised: zero powers dropped, sorted by lag then channel, merged") {
    const Moment m({{2, 1, 4}, {0, 0, 1}, {1, 1, 3}, {2, 2, 4}, {0, 1, 4}});
    CHECK(m.factors() == std::vector<MomentFactor>{{1, 1, 0}, {0, 1, 1}, {2, 3, 1}});
    CHECK(m.degree() == 5);
    CHECK(m.max_lag() == 1);
    CHECK(m.is_lagged());
    CHECK(m.at_lag(0, 3) == momentid::Monomial{0, 1, 0});
    CHECK(m.at_lag(1, 3) == momentid::Monomial{1, 0, 3});
    CHECK(momentid::to_string(m) == "c1*c0(t-1)*c2^3(t-1)");
  }

  TEST_CASE("a moment shifted by a common lag is the same moment") {
    CHECK(Moment({{0, 1, 3}, {1, 2, 5}}) == Moment({{1, 2, 2}, {0, 1, 0}}));
    CHECK(Moment({{0, 2, 7}}) == Moment::from_monomial({2}));
    CHECK_FALSE(Moment({{0, 2, 7}}).is_lagged());
    CHECK(Moment({{0, 1, 0}, {1, 1, 1}}) != Moment({{0, 1, 1}, {1, 1, 0}}));
  }

  TEST_CASE("a monomial becomes a moment at lag 0, and equal moments are one key") {
    const Moment m = Moment::from_monomial({2, 0, 1});
    CHECK(m.factors() == std::vector<MomentFactor>{{0, 2, 0}, {2, 1, 0}});
    CHECK(m.degree() == 3);
    CHECK(m.max_lag() == 0);
    CHECK(m.at_lag(0, 3) == momentid::Monomial{2, 0, 1});
    CHECK(Moment::from_monomial({0, 0}) == Moment());
    CHECK(momentid::to_string(Moment()) == "1");
    const std::set<Moment> keys{m, Moment({{2, 1, 5}, {0, 1, 5}, {0, 1, 5}}), Moment()};
    CHECK(keys.size() == 2);
  }

  TEST_CASE("a negative power or channel is refused, naming the factor") {
    CHECK(std::string(error_from<std::invalid_argument>([] {
                        Moment({{0, -1, 0}});
                      }).what()) == "moment factor c0^-1: channel and power must not be negative");
    CHECK(std::string(error_from<std::invalid_argument>([] {
                        Moment({{-2, 1, 3}});
                      }).what()) ==
          "moment factor c-2(t-3): channel and power must not be negative");
  }

  TEST_CASE("a lagged moment is the trapezoidal average of its products from row L on") {
    // One run of 200 rows; the largest lag L is 5, so every moment averages intervals 5 .. 199,
    // each read with its most lagged factor L rows back (a moment at lag 3 is shifted by 2).
    const Record record = make_record({200});
    const std::vector<Moment> moments = lagged_moments();
    const auto got = momentid::estimates(one_pass(record, InputHold::kSample, moments), 1).mean;
    const std::size_t lag = 5, rows = record.rows();
    for (std::size_t i = 0; i < moments.size(); ++i) {
      const auto value = [&](std::size_t n) {
        double product = 1;
        const std::size_t shift = lag - static_cast<std::size_t>(moments[i].max_lag());
        for (const MomentFactor& f : moments[i].factors()) {
          product *=
              std::pow(record.row(n - shift - static_cast<std::size_t>(f.lag))[f.channel], f.power);
        }
        return product;
      };
      double sum = 0;
      for (std::size_t n = lag; n + 1 < rows; ++n) sum += 0.5 * (value(n) + value(n + 1));
      const double want = sum / static_cast<double>(rows - 1 - lag);
      INFO(to_string(moments[i]));
      CHECK(std::abs(got[i] - want) <= 1e-13 * std::abs(want));
    }
  }

  TEST_CASE("every stretch holds the trapezoidal sums of its own intervals") {
    // Sampled inputs: every moment is a whole product averaged by the trapezoidal rule. The
    // stretches (4 batches: 8 to 16 of them, their length doubled as the record grows) cut runs
    // anywhere, so the sums of each must be those of exactly its intervals, also for shards.
    const Record record = make_record({301, 3, 6, 7, 180, 1, 95, 2, 40});
    const std::vector<Moment> moments = lagged_moments();
    const std::size_t lag = 5;
    const std::vector<std::size_t> intervals = record.interval_rows(lag);
    const auto value = [&](const Moment& m, std::size_t row) {
      return record.product(m, row, lag);
    };
    std::vector<std::size_t> all(moments.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    momentid::PortableRandom random(/*seed=*/3, /*stream=*/0);
    for (const std::size_t shards : {1, 5, 40}) {
      const MomentAccumulator acc = accumulate(record, shards, random, InputHold::kSample, moments);
      INFO(shards, " shards");
      check_stretch_sums(
          acc, intervals, all,
          [&](const Moment& m, std::size_t n) { return 0.5 * (value(m, n) + value(m, n + 1)); },
          [](double want) { return 1e-12 * std::abs(want); });
    }
  }

  TEST_CASE(
      "without lags, every stretch holds its intervals' averages, held ones by cubic weights") {
    // Every moment of degree 0 to 3 and increments: formed a chunk of rows at a time. A product
    // with the held input is u[n] times the cubic rule's integral of its state part g over
    // [n, n + 1], one-sided at a run's first and last interval, the trapezoid in a run of two.
    const Record record = make_record({301, 3, 6, 7, 180, 1, 95, 2, 40, 33, 64});
    std::vector<Moment> moments = all_moments();
    moments.push_back(Moment::increment_of({1, 1, 1}));
    const auto part = [&](const Moment& m, std::size_t row, std::size_t first, std::size_t last) {
      double out = 1;
      for (const MomentFactor& f : m.factors()) {
        const auto c = static_cast<std::size_t>(f.channel);
        if (c >= first && c < last) out *= std::pow(record.row(row)[c], f.power);
      }
      return out;
    };
    const auto held = [&](const Moment& m, std::size_t n) {
      const auto g = [&](std::size_t row) { return part(m, row, 0, kStates); };
      const std::size_t begin =
          *(std::upper_bound(record.run_starts.begin(), record.run_starts.end(), n) - 1);
      const bool first = n == begin, last = n + 2 >= record.run_end(n);
      const double integral = first && last ? (g(n) + g(n + 1)) / 2
                              : first       ? (5 * g(n) + 8 * g(n + 1) - g(n + 2)) / 12
                              : last        ? (-g(n - 1) + 8 * g(n) + 5 * g(n + 1)) / 12
                                     : (-g(n - 1) + 13 * g(n) + 13 * g(n + 1) - g(n + 2)) / 24;
      return part(m, n, kStates, kChannels) * integral;
    };
    const auto value = [&](InputHold hold, const Moment& m, std::size_t n) {
      if (m.is_increment()) return part(m, n + 1, 0, kChannels) - part(m, n, 0, kChannels);
      const bool has_input = std::any_of(
          m.factors().begin(), m.factors().end(),
          [](const MomentFactor& f) { return static_cast<std::size_t>(f.channel) >= kStates; });
      if (hold == InputHold::kZeroOrderHold && has_input) return held(m, n);
      return 0.5 * (part(m, n, 0, kChannels) + part(m, n + 1, 0, kChannels));
    };
    std::vector<std::size_t> all(moments.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    momentid::PortableRandom random(/*seed=*/11, /*stream=*/0);
    for (InputHold hold : {InputHold::kSample, InputHold::kZeroOrderHold}) {
      for (const std::size_t shards : {1, 5, 40}) {
        const MomentAccumulator acc = accumulate(record, shards, random, hold, moments);
        INFO("hold ", static_cast<int>(hold), ", ", shards, " shards");
        check_stretch_sums(
            acc, record.interval_rows(0), all,
            [&](const Moment& m, std::size_t n) { return value(hold, m, n); },
            [](double want) { return 1e-12 * std::max(1.0, std::abs(want)); });
      }
    }
  }

  TEST_CASE("an increment sums g(n + 1) - g(n) over the intervals of each stretch") {
    // Increments of a state, of a product of states and of a product with the input (the whole
    // product, not held), beside held moments; stretches cut runs anywhere, also for shards.
    const Record record = make_record({301, 3, 6, 7, 180, 1, 95, 2, 40});
    const std::vector<momentid::Monomial> changed{{2, 0, 0}, {1, 1, 1}, {0, 1, 0}};
    std::vector<Moment> moments = all_moments();
    for (const auto& g : changed) moments.push_back(Moment::increment_of(g));
    CHECK(momentid::to_string(moments.back()) == "d(c1)");
    const std::vector<std::size_t> intervals = record.interval_rows(0);
    const auto value = [&](const Moment& m, std::size_t row) { return record.product(m, row, 0); };
    std::vector<std::size_t> increments;
    for (std::size_t i = all_moments().size(); i < moments.size(); ++i) increments.push_back(i);
    momentid::PortableRandom random(/*seed=*/5, /*stream=*/0);
    for (InputHold hold : {InputHold::kSample, InputHold::kZeroOrderHold}) {
      for (const std::size_t shards : {1, 6}) {
        const MomentAccumulator acc = accumulate(record, shards, random, hold, moments);
        INFO("hold ", static_cast<int>(hold), ", ", shards, " shards");
        check_stretch_sums(
            acc, intervals, increments,
            [&](const Moment& m, std::size_t n) { return value(m, n + 1) - value(m, n); },
            [](double) { return 1e-12; });
        const MomentAccumulator copy = MomentAccumulator::deserialize(acc.serialize());
        CHECK(copy.moments() == acc.moments());
        CHECK(copy.serialize() == acc.serialize());
      }
    }
    MomentAccumulator plain({Moment::from_monomial({1})}, 1, 0, InputHold::kSample, 1);
    const MomentAccumulator increment({Moment::increment_of({1})}, 1, 0, InputHold::kSample, 1);
    CHECK(error_from<momentid::Error>([&] { plain.merge(increment); }).what() ==
          std::string("cannot merge moment accumulators of different moments: moment 0 is c0 "
                      "here, d(c0) in the other"));
  }

  TEST_CASE("bytes of an increment with lagged factors, or of an unknown kind, are refused") {
    std::vector<std::uint8_t> bytes = tiny_bytes();
    bytes[45] = 2;  // the kind of the only moment
    CHECK(deserialize_error(bytes) ==
          "moment accumulator bytes: moment 0 of kind 2, expected 0 (a moment) or 1 (an "
          "increment)");
  }

  TEST_CASE("lagged moments of shards with their history merge to the one-pass moments") {
    // Runs shorter than the largest lag (they give no interval), cuts inside the first rows of
    // a run (the history is then the whole run so far), and both holds.
    const Record record = make_record({301, 3, 6, 7, 180, 1, 95});
    momentid::PortableRandom random(/*seed=*/11, /*stream=*/0);
    for (const InputHold hold : {InputHold::kSample, InputHold::kZeroOrderHold}) {
      const MomentAccumulator want = one_pass(record, hold, lagged_moments());
      for (const std::size_t shards : {2, 3, 7, 40}) {
        const auto cuts = random_cuts(random, record.rows(), shards - 1);
        CAPTURE(shards);
        check_same_moments(merged_shards(record, cuts, hold, lagged_moments()), want);
      }
    }
  }

  TEST_CASE("lagged moments formed a chunk at a time are those formed row by row") {
    // A moment of five factors sends the whole accumulator row by row through its blocks and
    // rings; without it every moment is formed a chunk of rows at a time. Both holds (the cubic
    // weights of held products at every lag), one pass and shards with their history.
    const Record record = make_record({301, 3, 6, 7, 180, 1, 95, 2, 40});
    std::vector<Moment> by_rows = lagged_moments();
    by_rows.push_back(Moment({{0, 1, 0}, {1, 1, 1}, {2, 1, 2}, {0, 1, 3}, {1, 1, 4}}));
    momentid::PortableRandom random(/*seed=*/13, /*stream=*/0);
    for (const InputHold hold : {InputHold::kSample, InputHold::kZeroOrderHold}) {
      for (const std::size_t shards : {1, 6}) {
        const auto cuts = random_cuts(random, record.rows(), shards - 1);
        const MomentAccumulator chunked = merged_shards(record, cuts, hold, lagged_moments());
        const MomentAccumulator rows = merged_shards(record, cuts, hold, by_rows);
        CAPTURE(shards);
        REQUIRE(chunked.stretches().size() == rows.stretches().size());
        for (std::size_t q = 0; q < rows.stretches().size(); ++q) {
          CHECK(chunked.stretches()[q].intervals == rows.stretches()[q].intervals);
          for (std::size_t i = 0; i < lagged_moments().size(); ++i) {
            const double want = rows.stretches()[q].sums[i];
            INFO("stretch ", q, ", ", to_string(rows.moments()[i]));
            CHECK(std::abs(chunked.stretches()[q].sums[i] - want) <=
                  1e-12 * std::max(1.0, std::abs(want)));
          }
        }
      }
    }
  }

  TEST_CASE("history is refused beyond the largest lag or outside a continued run") {
    MomentAccumulator acc(lagged_moments(), kStates, kInputs, InputHold::kSample, kBatches);
    const std::vector<double> rows(6 * kChannels, 1.0);
    CHECK(std::string(error_from<std::invalid_argument>([&] {
                        acc.start_run();
                        acc.add_history(rows.data(), 1);
                      }).what()) ==
          "MomentAccumulator::add_history: 1 history rows, expected at most 5 (the largest lag), "
          "right after continue_run()");
    acc.continue_run();
    CHECK_THROWS_AS(acc.add_history(rows.data(), 6), std::invalid_argument);
    acc.add_history(rows.data(), 5);
  }

  TEST_CASE("the accumulator refuses a moment of a channel it does not have") {
    const std::string message = error_from<std::invalid_argument>([] {
                                  MomentAccumulator({Moment::from_monomial({0, 1, 0, 1})}, kStates,
                                                    kInputs, InputHold::kSample, kBatches);
                                }).what();
    CHECK(message ==
          "moment c1*c3: the factor c3 names channel 3, expected a channel below 3 (2 states, 1 "
          "input)");
  }

  TEST_CASE("more than three lookahead rows, or rows added after them, are refused") {
    MomentAccumulator acc(all_moments(), kStates, kInputs, InputHold::kSample, kBatches);
    const Record record = make_record({10});
    acc.continue_run();
    acc.add(record.row(0), 4);
    acc.add_lookahead(record.row(4), 2);
    CHECK(std::string(error_from<std::invalid_argument>([&] {
                        acc.add_lookahead(record.row(6), 2);
                      }).what()) ==
          "MomentAccumulator::add_lookahead: 4 lookahead rows, expected at most 3");
    CHECK(std::string(error_from<std::logic_error>([&] { acc.add(record.row(6), 1); }).what()) ==
          "MomentAccumulator::add after add_lookahead: the lookahead rows end the shard");
  }

  TEST_CASE("the layout is pinned: tag, version, and the size of a tiny accumulator") {
    const std::vector<std::uint8_t> bytes = tiny_bytes();
    CHECK(bytes.size() == 138);
    CHECK(std::string(bytes.begin(), bytes.begin() + 8) == "MOMACCUM");
    CHECK(bytes[8] == 2);
  }

  TEST_CASE("truncated bytes are refused, naming the field and where it starts") {
    std::vector<std::uint8_t> bytes = tiny_bytes();
    bytes.pop_back();
    CHECK(deserialize_error(bytes) ==
          "truncated moment accumulator bytes: 137 bytes, but 3 stretches need at least 16 bytes "
          "each from byte 90");
    bytes.resize(40);
    CHECK(deserialize_error(bytes) ==
          "truncated moment accumulator bytes: 40 bytes, but the number of moments needs 8 bytes "
          "from byte 37");
    bytes.resize(3);
    CHECK(deserialize_error(bytes) ==
          "truncated moment accumulator bytes: 3 bytes, but the tag needs 8 bytes from byte 0");
  }

  TEST_CASE("a count larger than the bytes can hold is refused before anything is allocated") {
    std::vector<std::uint8_t> bytes = tiny_bytes();
    bytes[37 + 7] = 0x10;  // the number of moments, 2^60 + 1
    CHECK(deserialize_error(bytes) ==
          "truncated moment accumulator bytes: 138 bytes, but 1152921504606846977 moments need at "
          "least 4 bytes each from byte 45");
  }

  TEST_CASE("bytes with a wrong tag, version, hold, counts or trailing bytes are refused") {
    std::vector<std::uint8_t> bytes = tiny_bytes();
    bytes[0] = 'X';
    CHECK(deserialize_error(bytes) ==
          "not moment accumulator bytes: they start with 58 4f 4d 41 43 43 55 4d, expected the "
          "tag \"MOMACCUM\"");
    bytes = tiny_bytes();
    bytes[8] = 1;
    CHECK(deserialize_error(bytes) ==
          "moment accumulator bytes of layout version 1, expected version 2");
    bytes = tiny_bytes();
    bytes[28] = 7;
    CHECK(deserialize_error(bytes) ==
          "moment accumulator bytes: input hold 7, expected 0 (sample), 1 (zero-order hold) or 2 "
          "(zero-order hold, trapezoidal)");
    bytes = tiny_bytes();
    bytes[74] = 3;  // the interval count
    CHECK(deserialize_error(bytes) ==
          "moment accumulator bytes: 3 intervals counted, but the stretches hold 2");
    bytes = tiny_bytes();
    bytes.push_back(0);
    CHECK(deserialize_error(bytes) ==
          "moment accumulator bytes: 1 byte after the end of the layout at byte 138");
  }

  TEST_CASE("bytes naming a channel the accumulator does not have are refused") {
    std::vector<std::uint8_t> bytes = tiny_bytes();
    bytes[54] = 1;  // the channel of the only factor
    CHECK(deserialize_error(bytes) ==
          "moment accumulator bytes: moment c1: the factor c1 names channel 1, expected a "
          "channel below 1 (1 state, 0 inputs)");
  }

  TEST_CASE("corrupt bytes throw Error or deserialise, never anything else") {
    const Record record = make_record({20, 3});
    const std::vector<std::uint8_t> good = one_pass(record, InputHold::kZeroOrderHold).serialize();
    momentid::PortableRandom random(/*seed=*/3, /*stream=*/0);
    for (int trial = 0; trial < 2000; ++trial) {
      std::vector<std::uint8_t> bytes = good;
      const std::size_t at = static_cast<std::size_t>(random.uniform() * 120);
      bytes[at] = static_cast<std::uint8_t>(random.next());
      if (trial % 2) bytes.resize(static_cast<std::size_t>(random.uniform() * bytes.size()));
      try {
        MomentAccumulator::deserialize(bytes);
      } catch (const momentid::Error&) {
      }
    }
  }

  TEST_CASE("collapsing a finished accumulator keeps its sums in one stretch") {
    const Record record = make_record({200, 150});
    MomentAccumulator acc = one_pass(record, InputHold::kZeroOrderHold);
    const auto before = momentid::estimates(acc, kBatches);
    acc.collapse();
    CHECK(acc.stretches().size() == 2);  // the sums and the open stretch
    CHECK(acc.stretches().back().intervals == 0);
    const auto after = momentid::estimates(acc, kBatches);
    CHECK(after.intervals == before.intervals);
    for (std::size_t k = 0; k < before.mean.size(); ++k) {
      CHECK(after.mean[k] == doctest::Approx(before.mean[k]).epsilon(1e-13));
    }
    MomentAccumulator open(all_moments(), kStates, kInputs, InputHold::kSample, kBatches);
    open.add(record.row(0), 5);
    CHECK(std::string(error_from<momentid::Error>([&] { open.collapse(); }).what()) ==
          "cannot collapse a moment accumulator in the middle of a run: call finish() on it "
          "first");
  }

  TEST_CASE("an accumulator in the middle of a run is neither serialised nor merged") {
    MomentAccumulator acc(all_moments(), kStates, kInputs, InputHold::kSample, kBatches);
    const Record record = make_record({10});
    acc.add(record.row(0), 5);
    CHECK(std::string(error_from<momentid::Error>([&] { acc.serialize(); }).what()) ==
          "cannot serialise a moment accumulator in the middle of a run: call finish() first");
    MomentAccumulator other(all_moments(), kStates, kInputs, InputHold::kSample, kBatches);
    CHECK(std::string(error_from<momentid::Error>([&] { other.merge(acc); }).what()) ==
          "cannot merge a moment accumulator in the middle of a run: call finish() on it first");
  }

  TEST_CASE("accumulators of other moments, hold or channels are not merged") {
    MomentAccumulator acc({Moment::from_monomial({1, 0, 0}), Moment::from_monomial({0, 2, 0})},
                          kStates, kInputs, InputHold::kSample, kBatches);
    auto merge_error = [&](const MomentAccumulator& other) {
      return std::string(error_from<momentid::Error>([&] { acc.merge(other); }).what());
    };
    CHECK(merge_error(MomentAccumulator({Moment::from_monomial({1, 0, 0})}, kStates, kInputs,
                                        InputHold::kSample, kBatches)) ==
          "cannot merge moment accumulators of different moments: 2 here, 1 in the other");
    CHECK(merge_error(MomentAccumulator(
              {Moment::from_monomial({1, 0, 0}), Moment::from_monomial({0, 1, 1})}, kStates,
              kInputs, InputHold::kSample, kBatches)) ==
          "cannot merge moment accumulators of different moments: moment 1 is c1^2 here, c1*c2 "
          "in the other");
    CHECK(merge_error(MomentAccumulator(
              {Moment::from_monomial({1, 0, 0}), Moment::from_monomial({0, 2, 0})}, kStates,
              kInputs, InputHold::kZeroOrderHold, kBatches)) ==
          "cannot merge moment accumulators with different input holds: sample here, zero-order "
          "hold in the other");
    CHECK(merge_error(MomentAccumulator(
              {Moment::from_monomial({1, 0, 0}), Moment::from_monomial({0, 2, 0})}, 3, 0,
              InputHold::kSample, kBatches)) ==
          "cannot merge moment accumulators over different channels: 2 states and 1 input here, "
          "3 states and 0 inputs in the other");
  }
}

TEST_SUITE("integration filter") {
  // A sine of acceleration a = sin(w t) at 30 Hz, 2048 Hz sampling, corner 3 Hz: each output
  // row is the filtered channels at (taps - 1)/2 rows before its last input, the acceleration
  // through the Butterworth magnitude |H|, its integrals through |H|/(i w) and |H|/(i w)^2, to
  // the filter's tail.
  TEST_CASE("the integrals of a sine are the sine's through the same zero-phase high-pass") {
    const double dt = 1.0 / 2048, w = 2 * 3.141592653589793 * 30, wc = 2 * 3.141592653589793 * 3;
    momentid::IntegrationFilter filter({.corner = 3, .dt = dt, .integrals = {2, 1, 0}});
    const std::size_t taps = filter.warm_up() + 1, rows = taps + 50000;
    CHECK(taps % 2 == 1);
    std::vector<double> values;
    for (std::size_t n = 0; n < rows; ++n) {
      const double a = std::sin(w * static_cast<double>(n) * dt);
      values.insert(values.end(), {a, a, a});
    }
    // In pieces, as blocks come, then the rest of the run.
    filter.start_run();
    std::vector<double> out;
    filter.push(values.data(), 1000, out);
    CHECK(out.empty());
    filter.push(values.data() + 3000, 20000, out);
    filter.push(values.data() + 63000, rows - 21000, out);
    filter.flush(out);
    REQUIRE(out.size() == 3 * (rows - taps + 1));
    const double gain = 1 / std::sqrt(1 + std::pow(wc / w, 8));
    double worst = 0;
    for (std::size_t i = 0; i < out.size() / 3; ++i) {
      const double t = static_cast<double>(i + (taps - 1) / 2) * dt;
      worst = std::max({worst, std::abs(out[3 * i] + gain * std::sin(w * t) / (w * w)) * w * w,
                        std::abs(out[3 * i + 1] + gain * std::cos(w * t) / w) * w,
                        std::abs(out[3 * i + 2] - gain * std::sin(w * t))});
    }
    CHECK(worst < 1e-5);  // the truncated tails, 1e-10 of the largest tap each, summed
    // The noise gain of the acceleration's channel is the sum of |H|^2 over the band: near 1.
    CHECK(filter.noise_gain(2) == doctest::Approx(1).epsilon(0.01));
  }

  TEST_CASE("an offset on the acceleration leaves no drift in its integrals") {
    momentid::IntegrationFilter filter({.corner = 2, .dt = 1e-3, .integrals = {2, 1}});
    std::vector<double> values(2 * (filter.warm_up() + 100), 5.0), out;
    filter.start_run();
    filter.push(values.data(), values.size() / 2, out);
    filter.flush(out);
    REQUIRE(out.size() == 200);
    for (double x : out) CHECK(std::abs(x) < 1e-9);
  }

  TEST_CASE("a corner beyond Nyquist or an integral count above 2 is refused") {
    CHECK_THROWS_AS(momentid::IntegrationFilter({.corner = 600, .dt = 1e-3, .integrals = {2}}),
                    std::invalid_argument);
    CHECK_THROWS_AS(momentid::IntegrationFilter({.corner = 2, .dt = 1e-3, .integrals = {3}}),
                    std::invalid_argument);
  }
  // The convention SharedNoise::covariance relies on: output(t) = sum_j taps[j] input(t - j),
  // output row i standing at input row i + (taps - 1) / 2.
  TEST_CASE("a filtered channel's impulse response is its taps") {
    momentid::IntegrationFilter filter({.corner = 3, .dt = 1.0 / 2048, .integrals = {0, 2}});
    const std::size_t taps = filter.warm_up() + 1;
    std::vector<double> values(2 * 2 * taps, 0.0), out;
    values[2 * (taps - 1)] = values[2 * (taps - 1) + 1] = 1;
    filter.start_run();
    filter.push(values.data(), values.size() / 2, out);
    filter.flush(out);
    REQUIRE(out.size() >= 2 * taps);
    double worst = 0;
    for (std::size_t c = 0; c < 2; ++c) {
      const std::vector<double>& h = filter.taps(c);
      REQUIRE(h.size() == taps);
      double largest = 0;
      for (double x : h) largest = std::max(largest, std::abs(x));
      for (std::size_t i = 0; i < taps; ++i) {
        worst = std::max(worst, std::abs(out[2 * i + c] - h[i]) / largest);
      }
    }
    CHECK(worst < 1e-12);
  }
}

TEST_SUITE("shared noise") {
  // Channel 0 carries the noise through taps {1, 2}, channel 1 through {3, 4, 5}, channel 2 its
  // own: Cov(n0(t - s), n1(t)) = 2 sum_i k0[i] k1[i + s].
  TEST_CASE("the covariance of two channels' noise at a lag comes from their taps") {
    momentid::SharedNoise noise{
        .source = {0, 0, -1}, .taps = {{1, 2}, {3, 4, 5}, {}}, .variance = {2}};
    CHECK(noise.covariance(0, 1, 0) == 22);
    CHECK(noise.covariance(0, 1, 1) == 28);
    CHECK(noise.covariance(0, 1, 2) == 10);
    CHECK(noise.covariance(0, 1, 3) == 0);
    CHECK(noise.covariance(0, 1, -1) == 12);
    CHECK(noise.covariance(1, 0, 1) == 12);
    CHECK(noise.covariance(0, 0, 0) == 10);
    CHECK(noise.covariance(0, 2, 0) == 0);
    CHECK_FALSE(noise.shared(2, 2));
  }
}
