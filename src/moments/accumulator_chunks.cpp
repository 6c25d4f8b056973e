// The chunked accumulator (every moment of at most four factors, lags up to 60 rows): the products
// of the moments formed kChunk rows at a time, column by column, and every interval whose rows the
// chunk holds closed at once, moment by moment along the rows, where accumulator_rows.cpp goes
// row by row through blocks and rings. The intervals, their weights and the stretches are the
// same; only the order of the floating-point sums differs.

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <tuple>
#include <utility>
#include <vector>

#include "momentid/accumulator.hpp"
#include "moments/accumulator_layout.hpp"
#include "moments/kernel.hpp"

namespace momentid {
namespace {

// out[r] = the product of the columns f[0 .. count) (two to four) at row r, for r < rows and up
// to three rows past them (rows rounded up to a multiple of four): the columns have room for them
// (kChunk is a multiple of four), and what those rows hold is never read as data.
[[gnu::always_inline]] inline void column_product(double* out,
                                                  const std::array<const double*, 4>& f,
                                                  std::uint32_t count, std::size_t rows) {
#pragma GCC unroll 4
  for (std::size_t r = 0; r < rows; r += 4) {
    Four p = load_four(f[0] + r) * load_four(f[1] + r);
    if (count > 2) p *= load_four(f[2] + r);
    if (count > 3) p *= load_four(f[3] + r);
    store_four(out + r, p);
  }
}

// The sum of u[k] (w0 g[k - 1] + w1 g[k] + w2 g[k + 1] + w3 g[k + 2]) over k < count, the rows
// whose weight is 0 (Before, After false) not read: a run has none there.
template <bool Before, bool After>
[[gnu::always_inline]] inline double held_sum(const double* u, const double* g, std::size_t count,
                                              const std::array<double, 4>& w) {
  const auto term = [&](auto at) {
    auto integral = w[1] * at(g) + w[2] * at(g + 1);
    if constexpr (Before) integral = w[0] * at(g - 1) + integral;
    if constexpr (After) integral += w[3] * at(g + 2);
    return at(u) * integral;
  };
  Four lanes{};
  std::size_t k = 0;
#pragma GCC unroll 4
  for (; k + 4 <= count; k += 4) lanes += term([&](const double* p) { return load_four(p + k); });
  double sum = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  for (; k < count; ++k) sum += term([&](const double* p) { return p[k]; });
  return sum;
}

// The sum of p[k] over k < count.
[[gnu::always_inline]] inline double column_sum(const double* p, std::size_t count) {
  Four lanes{};
  std::size_t k = 0;
#pragma GCC unroll 4
  for (; k + 4 <= count; k += 4) lanes += load_four(p + k);
  double sum = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  for (; k < count; ++k) sum += p[k];
  return sum;
}

}  // namespace

// The columns of the chunk: the powers, then each product of two to four powers at their lags
// that a moment (or a held moment's state or input part) needs, once.
void MomentAccumulator::lay_out_chunks(const std::vector<Layout>& layouts) {
  // The largest lag, and the rows n - 1 .. n + 2 of the cubic weights before the chunk's.
  pad_ = max_lag_ + 4;
  stride_ = pad_ + kChunk;
  // The power table's columns first, every power of every channel; the row path's history of
  // them is not needed.
  std::uint32_t next = 0;
  for (const int p : max_power_) next += static_cast<std::uint32_t>(p) + 1;
  history_ = {};
  std::map<std::vector<std::pair<std::uint32_t, std::uint32_t>>, std::uint32_t> columns;
  // The product of the factors [first, last) of a layout: a power's own column for one, the
  // column of ones (power 0 of channel 0) for none, read `lag` rows back.
  struct ChunkPart {
    std::uint32_t column, lag;
  };
  const auto part = [&](const Layout& l, std::size_t first, std::size_t last) -> ChunkPart {
    if (first == last) return {0, 0};
    const auto lag = static_cast<std::uint32_t>(
        *std::min_element(l.lags.begin() + static_cast<std::ptrdiff_t>(first),
                          l.lags.begin() + static_cast<std::ptrdiff_t>(last)));
    std::vector<std::pair<std::uint32_t, std::uint32_t>> factors;
    for (std::size_t f = first; f < last; ++f) {
      factors.emplace_back(static_cast<std::uint32_t>(l.indices[f]),
                           static_cast<std::uint32_t>(l.lags[f]) - lag);
    }
    if (factors.size() == 1) return {factors[0].first, lag};
    std::sort(factors.begin(), factors.end());
    const auto [at, added] = columns.try_emplace(factors, next);
    if (added) {
      ChunkProduct product{next++, static_cast<std::uint32_t>(factors.size()), {}, {}};
      for (std::size_t f = 0; f < factors.size(); ++f) {
        std::tie(product.factors[f], product.lags[f]) = factors[f];
      }
      products_.push_back(product);
    }
    return {at->second, lag};
  };
  whole_.resize(moments_.size());
  held_input_.resize(increments_begin_);
  // A part's index in chunk_ for the run's interval 0, less chunk_base_ (sum_intervals).
  const auto index = [&](const ChunkPart& p) {
    return static_cast<std::ptrdiff_t>(p.column * stride_ + pad_ + max_lag_) -
           static_cast<std::ptrdiff_t>(p.lag);
  };
  for (std::size_t i = 0; i < moments_.size(); ++i) {
    const Layout& l = layouts[order_[i]];
    const bool held = i < increments_begin_;
    whole_[i] = index(part(l, 0, held ? l.state_factors : l.indices.size()));
    if (held) held_input_[i] = index(part(l, l.state_factors, l.indices.size()));
  }
  chunk_.assign(next * stride_, 1.0);
}

void MomentAccumulator::push_chunks(const double* rows, std::size_t count) {
  const std::size_t variables = states_ + inputs_;
  for (std::size_t first = 0; first < count; first += kChunk) {
    const std::size_t n = std::min(kChunk, count - first);
    form_chunk(rows + first * variables, n);
    seen_rows_ += n;
    // The first max_lag_ rows of a run only give the lagged factors.
    run_rows_ = seen_rows_ > max_lag_ ? seen_rows_ - max_lag_ : 0;
    // The intervals with the rows their cubic weights need; the run's last waits for its end.
    if (run_rows_ >= 3) close_chunked(next_close_, run_rows_ - 2);
  }
}

// Forms the columns of `count` (at most kChunk) rows of the run after the rows the chunk holds,
// keeping its last pad_ rows before them. The products are formed a multiple of four rows at a
// time: the rows past `count` are not read.
MOMENTID_KERNEL void MomentAccumulator::form_chunk(const double* rows, std::size_t count) {
  if (seen_rows_ > 0) {
    for (double* at = chunk_.data(); at < chunk_.data() + chunk_.size(); at += stride_) {
      for (std::size_t r = 0; r < pad_; ++r) at[r] = at[r + chunk_rows_];
    }
  }
  chunk_base_ = seen_rows_;
  chunk_rows_ = count;
  const auto column = [&](std::size_t index) { return chunk_.data() + index * stride_ + pad_; };
  const std::size_t variables = states_ + inputs_;
  for (std::size_t v = 0; v < variables; ++v) {
    double* power = column(power_offset_[v] + 1);
    const double* const value = power;
    for (std::size_t r = 0; r < count; ++r) power[r] = rows[r * variables + v];
    for (int e = 2; e <= max_power_[v]; ++e, power += stride_) {
      column_product(power + stride_, {power, value, nullptr, nullptr}, 2, count);
    }
  }
  for (const ChunkProduct& p : products_) {
    std::array<const double*, kChunkFactors> factors{};
    for (std::size_t f = 0; f < kChunkFactors; ++f) factors[f] = column(p.factors[f]) - p.lags[f];
    column_product(column(p.column), factors, p.count, count);
  }
}

// Closes the intervals [first, last) of the run, whose rows the chunk holds, that this
// accumulator owns (owns()), a stretch at a time.
void MomentAccumulator::close_chunked(std::size_t first, std::size_t last) {
  next_close_ = std::max(next_close_, last);
  // The intervals it owns are contiguous: those before (a continued run's first) and after
  // (the lookahead's) are few.
  while (first < last && !owns(first)) ++first;
  while (last > first && !owns(last - 1)) --last;
  for (std::size_t n = first; n < last;) {
    std::size_t& stretch = stretches_.intervals(stretches_.size() - 1);
    const std::size_t k = std::min(last - n, stretch_length_ - stretch);
    sum_intervals(n, n + k);
    stretch += k;
    intervals_ += k;
    n += k;
    if (stretch >= stretch_length_) close_stretch();
  }
}

// Adds the averages of the intervals [first, last) of the run to the open sums (as
// close_interval and the plain sums of push_row do): the held moments with the weights of
// held_weights, the run's first and last intervals with their own; the increments' g at `last`
// less g at `first`; the other products by the trapezoidal rule.
MOMENTID_KERNEL void MomentAccumulator::sum_intervals(std::size_t first, std::size_t last) {
  const std::size_t rows = run_rows_;
  const bool cubic = rule_ == HeldRule::kCubic;
  const double* const chunk = chunk_.data();
  const auto base = static_cast<std::ptrdiff_t>(chunk_base_);
  // A part from interval `n`'s row on (max_lag_ rows into the run for interval 0).
  const auto at = [&](std::ptrdiff_t part, std::size_t n) {
    return chunk + (part + (static_cast<std::ptrdiff_t>(n) - base));
  };
  double* sums = open_sums_.data();
  // The interior intervals [inner, outer) share one set of weights; a run's first and last
  // have their own.
  const std::size_t inner = std::max<std::size_t>(first, 1);
  const std::size_t outer = std::max(inner, std::min(last, rows - 2));
  for (const auto& [a, b] : {std::pair{first, std::min<std::size_t>(first + 1, inner)},
                             std::pair{inner, outer}, std::pair{outer, last}}) {
    if (a >= b) continue;
    const std::array<double, 4> w = held_weights(a, rows, cubic);
    const bool before = w[0] != 0, after = w[3] != 0;
    for (std::size_t i = 0; i < increments_begin_; ++i) {
      const double* g = at(whole_[i], a);
      const double* u = at(held_input_[i], a);
      sums[i] += before && after ? held_sum<true, true>(u, g, b - a, w)
                 : before        ? held_sum<true, false>(u, g, b - a, w)
                 : after         ? held_sum<false, true>(u, g, b - a, w)
                                 : held_sum<false, false>(u, g, b - a, w);
    }
  }
  for (std::size_t i = increments_begin_; i < ringed_count_; ++i) {
    sums[i] += *at(whole_[i], last) - *at(whole_[i], first);
  }
  for (std::size_t i = ringed_count_; i < moments_.size(); ++i) {
    const double* p = at(whole_[i], first);
    sums[i] += 0.5 * p[0] + column_sum(p + 1, last - first - 1) + 0.5 * p[last - first];
  }
}

}  // namespace momentid
