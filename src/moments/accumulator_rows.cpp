// The per-row work of a MomentAccumulator: the powers of each new row into the history, the
// products of the moments from them, the trapezoidal sums of the plain moments as the rows
// arrive, and the closing of each interval with its held-input weights.

#include <algorithm>
#include <array>

#include "momentid/accumulator.hpp"
#include "moments/kernel.hpp"

namespace momentid {
namespace {

constexpr double kOne = 1.0;  // the value of a moment without factors

// The m-th value of a block factor at `p`: the same row for step 0, successive rows for 1 and
// -1 (newer and older).
template <int Step>
[[gnu::always_inline]] inline double factor_at(const double* p, std::size_t m) {
  if constexpr (Step == 0) {
    return p[0];
  } else if constexpr (Step == 1) {
    return p[m];
  } else {
    return *(p - m);
  }
}

// out[m] = p(m) or out[m] = p(m) * q(m) (with Add: out[m] += ...), or out[m] *= p(m), for
// m < n.
template <bool Add, int S>
[[gnu::always_inline]] inline void set(double* out, const double* p, std::size_t n) {
  for (std::size_t m = 0; m < n; ++m) {
    if constexpr (Add) {
      out[m] += factor_at<S>(p, m);
    } else {
      out[m] = factor_at<S>(p, m);
    }
  }
}
template <bool Add, int S, int T>
[[gnu::always_inline]] inline void set(double* out, const double* p, const double* q,
                                       std::size_t n) {
  for (std::size_t m = 0; m < n; ++m) {
    if constexpr (Add) {
      out[m] += factor_at<S>(p, m) * factor_at<T>(q, m);
    } else {
      out[m] = factor_at<S>(p, m) * factor_at<T>(q, m);
    }
  }
}
template <int S>
[[gnu::always_inline]] inline void multiply(double* out, const double* p, std::size_t n) {
  for (std::size_t m = 0; m < n; ++m) out[m] *= factor_at<S>(p, m);
}

// out[m] (+)= the product of one or two factors at p and q (q null with one).
template <bool Add>
[[gnu::always_inline]] inline void set(double* out, int s, const double* p, int t, const double* q,
                                       std::size_t n) {
  if (q == nullptr) {
    if (s == 0) set<Add, 0>(out, p, n);
    if (s == 1) set<Add, 1>(out, p, n);
    if (s == -1) set<Add, -1>(out, p, n);
    return;
  }
  if (s == 0 && t == 0) set<Add, 0, 0>(out, p, q, n);
  if (s == 0 && t == 1) set<Add, 0, 1>(out, p, q, n);
  if (s == 0 && t == -1) set<Add, 0, -1>(out, p, q, n);
  if (s == 1 && t == 0) set<Add, 1, 0>(out, p, q, n);
  if (s == 1 && t == 1) set<Add, 1, 1>(out, p, q, n);
  if (s == 1 && t == -1) set<Add, 1, -1>(out, p, q, n);
  if (s == -1 && t == 0) set<Add, -1, 0>(out, p, q, n);
  if (s == -1 && t == 1) set<Add, -1, 1>(out, p, q, n);
  if (s == -1 && t == -1) set<Add, -1, -1>(out, p, q, n);
}

}  // namespace

// In the order of the block loops below (1 times the first factor is that factor).
[[gnu::always_inline]] inline double MomentAccumulator::single_product(const Single& one,
                                                                       const double* history,
                                                                       std::uint32_t first,
                                                                       std::uint32_t last) {
  double p = 1.0;
  for (std::uint32_t f = first; f < last; ++f) p *= history[one.offsets[f]];
  return p;
}

// out[m] = the product of the block's factors [first, last) for its m-th member, 1 with none;
// the first two factors in one sweep, since most moments have two.
MOMENTID_KERNEL void MomentAccumulator::product(double* out, const Block& b, const double* history,
                                                std::size_t first, std::size_t last) {
  const auto at = [&](std::size_t f) { return history + b.factors[f].offset; };
  if (first == last) {
    std::fill(out, out + b.size, 1.0);
    return;
  }
  const bool two = first + 1 < last;
  set<false>(out, b.factors[first].step, at(first), two ? b.factors[first + 1].step : 0,
             two ? at(first + 1) : nullptr, b.size);
  for (std::size_t f = first + 2; f < last; ++f) {
    const int u = b.factors[f].step;
    if (u == 0) multiply<0>(out, at(f), b.size);
    if (u == 1) multiply<1>(out, at(f), b.size);
    if (u == -1) multiply<-1>(out, at(f), b.size);
  }
}

// Stores the powers of `row` as the newest row of the history.
inline void MomentAccumulator::store_powers(const double* row) {
  const std::size_t depth = max_lag_ + 2;
  const std::size_t span = 2 * depth;
  history_pos_ = (history_pos_ + depth - 1) % depth;
  for (std::size_t v = 0; v < states_ + inputs_; ++v) {
    double power = row[v];
    for (int e = 1; e <= max_power_[v]; ++e) {
      double* at = history_.data() + (power_offset_[v] + static_cast<std::size_t>(e)) * span;
      at[history_pos_] = power;
      at[history_pos_ + depth] = power;
      power *= row[v];
    }
  }
}

void MomentAccumulator::push_rows(const double* rows, std::size_t count) {
  if (chunked_) {
    push_chunks(rows, count);
    return;
  }
  const std::size_t variables = states_ + inputs_;
  for (std::size_t r = 0; r < count; ++r) push_row(rows + r * variables);
}

void MomentAccumulator::push_row(const double* row) {
  store_powers(row);
  ++seen_rows_;
  // The first max_lag_ rows of a run only fill the history.
  if (seen_rows_ <= max_lag_) return;
  const std::size_t m = run_rows_;
  const double* history = history_.data() + history_pos_;
  // A held moment keeps its state and input parts apart (the state part is integrated over
  // the interval, the input held), in the rings for close_interval.
  double* state = state_ring_.data() + (m % 4) * ringed_count_;
  double* input = input_ring_.data() + (m % 4) * ringed_count_;
  for (const Single& one : held_singles_) {
    state[one.position] = single_product(one, history, 0, one.state_factors);
    input[one.position] = single_product(one, history, one.state_factors, one.factors);
  }
  for (const std::size_t i : held_blocks_) {
    const Block& b = blocks_[i];
    product(state + b.begin, b, history, 0, b.state_factors);
    product(input + b.begin, b, history, b.state_factors, b.factors.size());
  }
  // Any other moment is the product of all its factors, averaged over the intervals by the
  // trapezoidal rule as the rows arrive: over consecutive intervals added to the same sums,
  // each row but the first and the last has weight 1. Row m ends interval m - 1.
  if (m >= 1 && owns(m - 1)) {
    if (!plain_open_) {
      plain_products(previous_row_.data(), history + 1);
      add_plain(previous_row_, 0.5);
      plain_open_ = true;
    }
    add_plain_products(history);
  } else if (plain_open_) {
    plain_products(previous_row_.data(), history + 1);
    add_plain(previous_row_, -0.5);
    plain_open_ = false;
  }
  ++run_rows_;
  // With rows up to m known, the interval [m - 2, m - 1] can be closed.
  if (m >= 2) close_interval(m - 2);
}

// Adds the products of the moments without a held input at the row `history` starts at to the
// open sums, the products of one or two factors (most) without storing them.
MOMENTID_KERNEL void MomentAccumulator::add_plain_products(const double* history) {
  double* sums = open_sums_.data();
  for (const Single& one : plain_singles_) {
    sums[one.position] += single_product(one, history, 0, one.factors);
  }
  for (const std::size_t i : plain_blocks_) {
    const Block& b = blocks_[i];
    const std::size_t n = b.factors.size();
    if (n <= 2) {
      const auto at = [&](std::size_t f) { return history + b.factors[f].offset; };
      set<true>(sums + b.begin, n > 0 ? b.factors[0].step : 0, n > 0 ? at(0) : &kOne,
                n > 1 ? b.factors[1].step : 0, n > 1 ? at(1) : nullptr, b.size);
    } else {
      double* row = row_.data() + b.begin;
      product(row, b, history, 0, n);
      for (std::size_t m = 0; m < b.size; ++m) sums[b.begin + m] += row[m];
    }
  }
}

void MomentAccumulator::plain_products(double* out, const double* history) const {
  for (const Block& b : blocks_) {
    if (b.begin >= ringed_count_) product(out + b.begin, b, history, 0, b.factors.size());
  }
}

void MomentAccumulator::add_plain(const std::vector<double>& row, double weight) {
  double* sums = open_sums_.data();
  for (std::size_t i = ringed_count_; i < row.size(); ++i) sums[i] += weight * row[i];
}

// Interval n starts at row j = n + max_lag_ of those this accumulator saw in the run. It
// belongs to the shard that holds row j - 1 (the first interval of a run: the shard that
// started the run), so that each shard closes its intervals with its own rows, its history and
// at most kLookaheadRows rows past its end.
bool MomentAccumulator::owns(std::size_t n) const {
  const std::size_t j = n + max_lag_;
  return j == 0 ? !continued_ : j - 1 >= history_rows_ && j - 1 < history_rows_ + owned_rows_;
}

// Weights of g at rows n - 1, n, n + 1, n + 2 for the integral over interval n, [n, n + 1], of
// a run of `rows` rows so far, divided by dt.
std::array<double, 4> MomentAccumulator::held_weights(std::size_t n, std::size_t rows, bool cubic) {
  if (cubic && n >= 1 && n + 2 < rows) return {-1.0 / 24, 13.0 / 24, 13.0 / 24, -1.0 / 24};
  if (cubic && n + 2 < rows) return {0, 5.0 / 12, 8.0 / 12, -1.0 / 12};  // a run's first
  if (cubic && n >= 1) return {-1.0 / 12, 8.0 / 12, 5.0 / 12, 0};        // a run's last
  return {0, 0.5, 0.5, 0};
}

// Closes interval n, between rows n and n + 1 of the run: adds the averages of its held moments
// to the open sums and counts it. A product with a held input is u[n] times the integral of g(y)
// over the interval; the trapezoidal rule would leave an error -dt^2/12 * E[u g''] that does not
// average out, so g is integrated by the cubic through the rows n - 1 .. n + 2 (one-sided at the
// ends of a run). Where g has a kink at every row (a state whose derivative contains the held
// input) an O(dt^2) remainder stays, smaller than the trapezoidal rule's: this is the bias of
// coarse sampling that `identify` warns about, unless it corrects it from the model: then g is
// integrated by the trapezoidal rule (HeldRule::kTrapezoidal), whose error the correction
// removes. The other products are continuous across rows: push_rows adds them by the
// trapezoidal rule, whose error accumulates only at the ends of a run where they are smooth, and
// at every row where the held input makes their derivative jump (corrected the same way).
MOMENTID_KERNEL void MomentAccumulator::close_interval(std::size_t n) {
  if (!owns(n)) return;
  const std::size_t rows = run_rows_;
  auto state = [&](std::size_t row) { return state_ring_.data() + (row % 4) * ringed_count_; };
  const double* g0 = state(n);
  const double* g1 = state(n + 1);
  const double* h0 = input_ring_.data() + (n % 4) * ringed_count_;
  const std::array<double, 4> w = held_weights(n, rows, rule_ == HeldRule::kCubic);
  const double* gm = n >= 1 ? state(n - 1) : g0;
  const double* g2 = n + 2 < rows ? state(n + 2) : g1;
  double* sums = open_sums_.data();
  if (w[0] == 0 && w[3] == 0) {
    // The trapezoidal rule: the same sums, the terms that add 0 left out.
    for (std::size_t i = 0; i < increments_begin_; ++i) {
      sums[i] += h0[i] * (w[1] * g0[i] + w[2] * g1[i]);
    }
  } else {
    for (std::size_t i = 0; i < increments_begin_; ++i) {
      sums[i] += h0[i] * (w[0] * gm[i] + w[1] * g0[i] + w[2] * g1[i] + w[3] * g2[i]);
    }
  }
  for (std::size_t i = increments_begin_; i < ringed_count_; ++i) sums[i] += g1[i] - g0[i];
  ++intervals_;
  if (++stretches_.intervals(stretches_.size() - 1) >= stretch_length_) close_stretch();
}

// The open stretch is full: starts the next. The plain sums may hold the interval after the one
// just closed already (the newest row and half of the row before, which began it): that goes to
// the next stretch.
void MomentAccumulator::close_stretch() {
  const bool carry = plain_open_;
  if (carry) {
    plain_products(row_.data(), history_.data() + history_pos_);
    plain_products(previous_row_.data(), history_.data() + history_pos_ + 1);
    add_plain(row_, -1.0);
    add_plain(previous_row_, -0.5);
  }
  flush();
  if (carry) {
    add_plain(row_, 1.0);
    add_plain(previous_row_, 0.5);
  }
  open_stretch();
  if (stretches_.size() > max_stretches_) compact();
}

}  // namespace momentid
