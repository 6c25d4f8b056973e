#include "momentid/accumulator.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>

#include "common/bytes.hpp"

// The per-row kernels are also built for AVX2, chosen when the program loads on a processor
// that has it. Without fused multiply-adds both builds compute the same numbers. (GCC only:
// clang refuses clones of functions declared before, as these are, in the class.)
#if defined(__x86_64__) && defined(__gnu_linux__) && !defined(__clang__)
#define MOMENTID_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#define MOMENTID_KERNEL
#endif

namespace momentid {
namespace {

// "1 state", "2 states".
std::string count_of(std::size_t n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

}  // namespace

MomentAccumulator::MomentAccumulator(std::vector<Moment> moments, std::size_t states,
                                     std::size_t inputs, InputHold hold, std::size_t batches,
                                     HeldRule rule)
    : moments_(std::move(moments)),
      states_(states),
      inputs_(inputs),
      hold_(hold),
      rule_(hold == InputHold::kZeroOrderHold ? rule : HeldRule::kCubic),
      batches_(batches),
      max_stretches_(4 * std::max<std::size_t>(batches, 2)) {
  const std::size_t variables = states_ + inputs_;
  for (const Moment& m : moments_) {
    for (const MomentFactor& f : m.factors()) {
      if (static_cast<std::size_t>(f.channel) >= variables) {
        throw std::invalid_argument(
            "moment " + to_string(m) + ": the factor " + to_string(f) + " names channel " +
            std::to_string(f.channel) + ", expected a channel below " + std::to_string(variables) +
            " (" + count_of(states_, "state") + ", " + count_of(inputs_, "input") + ")");
      }
      max_lag_ = std::max(max_lag_, static_cast<std::size_t>(f.lag));
    }
  }
  max_power_.assign(variables, 1);
  for (const Moment& m : moments_) {
    for (const MomentFactor& f : m.factors()) {
      max_power_[f.channel] = std::max(max_power_[f.channel], f.power);
    }
  }
  std::size_t offset = 0;
  for (int p : max_power_) {
    power_offset_.push_back(offset);
    offset += static_cast<std::size_t>(p) + 1;
  }
  // Every power of every channel over the last max_lag_ + 2 rows (the moments of the row before
  // the newest are recomputed at the ends of the stretches), newest first, stored twice in a row
  // so that the rows back from any start are contiguous.
  const std::size_t depth = max_lag_ + 2;
  history_.assign(offset * 2 * depth, 1.0);

  // Each moment's factors as (lag, power-table index), state factors first. A moment is read
  // with its most lagged factor max_lag_ rows back: the products at every lag then share one
  // window of times for that factor (the instrument), and a stencil over lags of
  // C[ψ;F](s) = E[ψ(t − s) F(t)] is exactly the stencil applied to F at each instrument time,
  // with no end effects; reading F at a fixed window instead would leave end terms that a
  // derivative in s multiplies by 1/dt^2.
  // Kinds in working order: products with a held input, increments, the other products.
  enum Kind { kHeld, kIncrement, kPlain };
  struct Layout {
    Kind kind = kPlain;
    std::size_t state_factors = 0;
    std::vector<std::size_t> indices, lags;
  };
  std::vector<Layout> layouts(moments_.size());
  for (std::size_t i = 0; i < moments_.size(); ++i) {
    Layout& l = layouts[i];
    const std::size_t shift = max_lag_ - static_cast<std::size_t>(moments_[i].max_lag());
    bool has_input = false;
    for (bool state_part : {true, false}) {
      for (const MomentFactor& f : moments_[i].factors()) {
        if ((static_cast<std::size_t>(f.channel) < states_) != state_part) continue;
        l.indices.push_back(power_offset_[f.channel] + static_cast<std::size_t>(f.power));
        l.lags.push_back(static_cast<std::size_t>(f.lag) + shift);
        has_input = has_input || !state_part;
      }
      if (state_part) l.state_factors = l.indices.size();
    }
    if (moments_[i].is_increment()) {
      l.kind = kIncrement;  // the whole product at each row, kept in the rings
      l.state_factors = l.indices.size();
    } else if (hold_ == InputHold::kZeroOrderHold && has_input) {
      l.kind = kHeld;
    }
  }
  // The moments are worked on in an order that puts the held ones first, then the increments,
  // and lines up the same factors at successive lags, so that blocks of them are products of
  // contiguous rows.
  order_.resize(moments_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
  std::stable_sort(order_.begin(), order_.end(), [&](std::size_t x, std::size_t y) {
    const Layout& a = layouts[x];
    const Layout& b = layouts[y];
    if (a.kind != b.kind) return a.kind < b.kind;
    return std::tie(a.state_factors, a.indices, a.lags) <
           std::tie(b.state_factors, b.indices, b.lags);
  });
  const auto count = [&](Kind kind) {
    return static_cast<std::size_t>(std::count_if(layouts.begin(), layouts.end(),
                                                  [&](const Layout& l) { return l.kind == kind; }));
  };
  increments_begin_ = count(kHeld);
  ringed_count_ = increments_begin_ + count(kIncrement);
  const std::size_t span = 2 * depth;
  for (std::size_t q = 0; q < order_.size();) {
    const Layout& first = layouts[order_[q]];
    std::vector<long> steps;
    std::size_t end = q + 1;
    for (; end < order_.size(); ++end) {
      const Layout& prev = layouts[order_[end - 1]];
      const Layout& next = layouts[order_[end]];
      if (next.kind != first.kind || next.state_factors != first.state_factors ||
          next.indices != first.indices) {
        break;
      }
      std::vector<long> d(next.lags.size());
      bool unit = true;
      for (std::size_t f = 0; f < d.size(); ++f) {
        d[f] = static_cast<long>(next.lags[f]) - static_cast<long>(prev.lags[f]);
        unit = unit && d[f] >= -1 && d[f] <= 1;
      }
      if (!unit || (end > q + 1 && d != steps)) break;
      steps = d;
    }
    Block block{q, end - q, first.state_factors, {}};
    for (std::size_t f = 0; f < first.indices.size(); ++f) {
      block.factors.push_back({first.indices[f] * span + first.lags[f],
                               steps.empty() ? 0 : static_cast<int>(steps[f])});
    }
    blocks_.push_back(std::move(block));
    q = end;
  }
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    const Block& b = blocks_[i];
    const bool ringed = b.begin < ringed_count_;
    const std::size_t n = b.factors.size();
    // A held moment needs both parts; one without an input factor is not held. An increment
    // (all state part) is computed by blocks.
    const bool fits = std::all_of(b.factors.begin(), b.factors.end(), [](const BlockFactor& f) {
      return f.offset <= std::numeric_limits<std::uint32_t>::max();
    });
    if (b.size == 1 && n >= 1 && n <= 4 && fits &&
        (!ringed || (b.state_factors > 0 && b.state_factors < n))) {
      Single single{static_cast<std::uint32_t>(b.begin),
                    static_cast<std::uint32_t>(b.state_factors),
                    static_cast<std::uint32_t>(n),
                    {}};
      for (std::size_t f = 0; f < n; ++f) {
        single.offsets[f] = static_cast<std::uint32_t>(b.factors[f].offset);
      }
      (ringed ? held_singles_ : plain_singles_).push_back(single);
    } else {
      (ringed ? held_blocks_ : plain_blocks_).push_back(i);
    }
  }
  const std::size_t k = moments_.size();
  state_ring_.assign(4 * ringed_count_, 0.0);
  input_ring_.assign(4 * ringed_count_, 0.0);
  row_.assign(k, 0.0);
  previous_row_.assign(k, 0.0);
  open_sums_.assign(k, 0.0);
  stretches_.push_back({std::vector<double>(k, 0.0), 0});
}

void MomentAccumulator::start_run() { finish_run(); }

void MomentAccumulator::continue_run() {
  finish_run();
  continued_ = true;
}

void MomentAccumulator::add_history(const double* rows, std::size_t count) {
  if (!continued_ || owned_rows_ > 0 || lookahead_rows_ > 0 || history_rows_ + count > max_lag_) {
    throw std::invalid_argument(
        "MomentAccumulator::add_history: " + std::to_string(history_rows_ + count) +
        " history rows, expected at most " + std::to_string(max_lag_) +
        " (the largest lag), right after continue_run()");
  }
  history_rows_ += count;
  push_rows(rows, count);
}

void MomentAccumulator::finish() { finish_run(); }

// Closes the interval between the last two rows given, the last of the run unless it lies in
// the lookahead (then close_interval skips it), and forgets the run.
void MomentAccumulator::finish_run() {
  if (plain_open_) {
    // The last row of the run ends the last interval of the plain sums: it has weight 1/2.
    plain_products(row_.data(), history_.data() + history_pos_);
    add_plain(row_, -0.5);
    plain_open_ = false;
  }
  if (run_rows_ >= 2) close_interval(run_rows_ - 2);
  flush();
  run_rows_ = 0;
  seen_rows_ = 0;
  continued_ = false;
  history_rows_ = 0;
  owned_rows_ = 0;
  lookahead_rows_ = 0;
}

void MomentAccumulator::add(const double* rows, std::size_t count) {
  if (lookahead_rows_ > 0) {
    throw std::logic_error(
        "MomentAccumulator::add after add_lookahead: the lookahead rows end the shard");
  }
  owned_rows_ += count;
  push_rows(rows, count);
}

void MomentAccumulator::add_lookahead(const double* rows, std::size_t count) {
  if (lookahead_rows_ + count > kLookaheadRows) {
    throw std::invalid_argument(
        "MomentAccumulator::add_lookahead: " + std::to_string(lookahead_rows_ + count) +
        " lookahead rows, expected at most " + std::to_string(kLookaheadRows));
  }
  lookahead_rows_ += count;
  push_rows(rows, count);
}

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

// In the order of the block loops below.
[[gnu::always_inline]] inline double MomentAccumulator::single_product(const Single& one,
                                                                       const double* history,
                                                                       std::uint32_t first,
                                                                       std::uint32_t last) {
  double p = history[one.offsets[first]];
  for (std::uint32_t f = first + 1; f < last; ++f) p *= history[one.offsets[f]];
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

void MomentAccumulator::push_rows(const double* rows, std::size_t count) {
  const std::size_t variables = states_ + inputs_;
  const std::size_t depth = max_lag_ + 2;
  const std::size_t span = 2 * depth;
  for (std::size_t r = 0; r < count; ++r) {
    const double* row = rows + r * variables;
    history_pos_ = (history_pos_ + depth - 1) % depth;
    for (std::size_t v = 0; v < variables; ++v) {
      double power = row[v];
      for (int e = 1; e <= max_power_[v]; ++e) {
        double* at = history_.data() + (power_offset_[v] + static_cast<std::size_t>(e)) * span;
        at[history_pos_] = power;
        at[history_pos_ + depth] = power;
        power *= row[v];
      }
    }
    ++seen_rows_;
    // The first max_lag_ rows of a run only fill the history.
    if (seen_rows_ <= max_lag_) continue;
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
  // Weights of g at rows n - 1, n, n + 1, n + 2 for the integral over [n, n + 1] / dt.
  double w[4] = {0, 0.5, 0.5, 0};
  const bool cubic = rule_ == HeldRule::kCubic;
  if (cubic && n >= 1 && n + 2 < rows) {
    w[0] = -1.0 / 24;
    w[1] = 13.0 / 24;
    w[2] = 13.0 / 24;
    w[3] = -1.0 / 24;
  } else if (cubic && n + 2 < rows) {  // first interval of the run
    w[1] = 5.0 / 12;
    w[2] = 8.0 / 12;
    w[3] = -1.0 / 12;
  } else if (cubic && n >= 1) {  // last interval of the run
    w[0] = -1.0 / 12;
    w[1] = 8.0 / 12;
    w[2] = 5.0 / 12;
  }
  const double* gm = n >= 1 ? state(n - 1) : g0;
  const double* g2 = n + 2 < rows ? state(n + 2) : g1;
  double* sums = open_sums_.data();
  for (std::size_t i = 0; i < increments_begin_; ++i) {
    sums[i] += h0[i] * (w[0] * gm[i] + w[1] * g0[i] + w[2] * g1[i] + w[3] * g2[i]);
  }
  for (std::size_t i = increments_begin_; i < ringed_count_; ++i) sums[i] += g1[i] - g0[i];
  Stretch& stretch = stretches_.back();
  ++stretch.intervals;
  ++intervals_;
  if (stretch.intervals < stretch_length_) return;
  // The stretch is full. The plain sums may hold interval n + 1 already (the newest row n + 2
  // and half of row n + 1, which began it): that goes to the next stretch.
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
  stretches_.push_back({std::vector<double>(moments_.size(), 0.0), 0});
  if (stretches_.size() > max_stretches_) compact();
}

// Adds the sums of the open stretch, kept in working order, to its stretch.
void MomentAccumulator::flush() {
  std::vector<double>& sums = stretches_.back().sums;
  for (std::size_t i = 0; i < open_sums_.size(); ++i) {
    sums[order_[i]] += open_sums_[i];
    open_sums_[i] = 0;
  }
}

// Halves the number of stretches by adding neighbours; the open (last) stretch stays last.
void MomentAccumulator::collapse() {
  if (seen_rows_ > 0) {
    throw Error(
        "cannot collapse a moment accumulator in the middle of a run: call finish() on it "
        "first");
  }
  Stretch whole{std::vector<double>(moments_.size(), 0.0), 0};
  for (const Stretch& s : stretches_) {
    for (std::size_t j = 0; j < s.sums.size(); ++j) whole.sums[j] += s.sums[j];
    whole.intervals += s.intervals;
  }
  stretches_.clear();
  if (whole.intervals > 0) stretches_.push_back(std::move(whole));
  stretches_.push_back({std::vector<double>(moments_.size(), 0.0), 0});
}

void MomentAccumulator::compact() {
  std::vector<Stretch> merged;
  const std::size_t closed = stretches_.size() - 1;
  for (std::size_t i = 0; i + 1 < closed; i += 2) {
    Stretch s = stretches_[i];
    for (std::size_t j = 0; j < s.sums.size(); ++j) s.sums[j] += stretches_[i + 1].sums[j];
    s.intervals += stretches_[i + 1].intervals;
    merged.push_back(std::move(s));
  }
  if (closed % 2 == 1) {
    // An odd one out starts the open stretch, which is then at most one old length long.
    Stretch s = stretches_[closed - 1];
    for (std::size_t j = 0; j < s.sums.size(); ++j) s.sums[j] += stretches_.back().sums[j];
    s.intervals += stretches_.back().intervals;
    merged.push_back(std::move(s));
  } else {
    merged.push_back(std::move(stretches_.back()));
  }
  stretches_ = std::move(merged);
  stretch_length_ *= 2;
}

namespace {

const char* hold_name(InputHold hold, HeldRule rule) {
  if (hold == InputHold::kSample) return "sample";
  return rule == HeldRule::kCubic ? "zero-order hold" : "zero-order hold (trapezoidal)";
}

std::string channel_counts(std::size_t states, std::size_t inputs) {
  return count_of(states, "state") + " and " + count_of(inputs, "input");
}

}  // namespace

void MomentAccumulator::merge(const MomentAccumulator& other) {
  if (this == &other) {
    // Appending its own stretches would read them while they grow.
    const MomentAccumulator copy = other;
    merge(copy);
    return;
  }
  if (other.seen_rows_ > 0) {
    throw Error(
        "cannot merge a moment accumulator in the middle of a run: call finish() on it first");
  }
  if (states_ != other.states_ || inputs_ != other.inputs_) {
    throw Error("cannot merge moment accumulators over different channels: " +
                channel_counts(states_, inputs_) + " here, " +
                channel_counts(other.states_, other.inputs_) + " in the other");
  }
  if (hold_ != other.hold_ || rule_ != other.rule_) {
    throw Error(std::string("cannot merge moment accumulators with different input holds: ") +
                hold_name(hold_, rule_) + " here, " + hold_name(other.hold_, other.rule_) +
                " in the other");
  }
  if (moments_.size() != other.moments_.size()) {
    throw Error("cannot merge moment accumulators of different moments: " +
                std::to_string(moments_.size()) + " here, " +
                std::to_string(other.moments_.size()) + " in the other");
  }
  for (std::size_t i = 0; i < moments_.size(); ++i) {
    if (moments_[i] != other.moments_[i]) {
      throw Error("cannot merge moment accumulators of different moments: moment " +
                  std::to_string(i) + " is " + to_string(moments_[i]) + " here, " +
                  to_string(other.moments_[i]) + " in the other");
    }
  }
  finish_run();
  if (stretches_.back().intervals == 0) stretches_.pop_back();
  for (const Stretch& s : other.stretches_) {
    if (s.intervals > 0) stretches_.push_back(s);
  }
  intervals_ += other.intervals_;
  stretches_.push_back({std::vector<double>(moments_.size(), 0.0), 0});
  while (stretches_.size() > max_stretches_) compact();
}

namespace {

constexpr char kTag[8] = {'M', 'O', 'M', 'A', 'C', 'C', 'U', 'M'};
constexpr std::uint32_t kLayoutVersion = 2;
// Bounds on what deserialize() accepts, so that corrupt counts cannot ask for huge tables.
constexpr std::uint64_t kMaxChannels = 4096;
constexpr int kMaxPower = 1024;

std::string hex(std::span<const std::uint8_t> bytes) {
  static const char digits[] = "0123456789abcdef";
  std::string out;
  for (std::uint8_t b : bytes) {
    if (!out.empty()) out += ' ';
    out += digits[b >> 4];
    out += digits[b & 15];
  }
  return out;
}

}  // namespace

std::vector<std::uint8_t> MomentAccumulator::serialize() const {
  if (seen_rows_ > 0) {
    throw Error(
        "cannot serialise a moment accumulator in the middle of a run: call finish() first");
  }
  ByteWriter out;
  out.bytes(kTag, sizeof kTag);
  out.u32(kLayoutVersion);
  out.u64(states_);
  out.u64(inputs_);
  out.u8(hold_ == InputHold::kSample ? 0 : rule_ == HeldRule::kCubic ? 1 : 2);
  out.u64(batches_);
  out.u64(moments_.size());
  for (const Moment& m : moments_) {
    out.u8(m.is_increment() ? 1 : 0);
    out.u64(m.factors().size());
    for (const MomentFactor& f : m.factors()) {
      out.i32(f.channel);
      out.i32(f.power);
      out.i32(f.lag);
    }
  }
  out.u64(stretch_length_);
  out.u64(intervals_);
  out.u64(stretches_.size());
  for (const Stretch& s : stretches_) {
    out.u64(s.intervals);
    for (double x : s.sums) out.f64(x);
  }
  return out.take();
}

MomentAccumulator MomentAccumulator::deserialize(std::span<const std::uint8_t> bytes) {
  ByteReader in(bytes, "moment accumulator bytes");
  const auto tag = in.take(sizeof kTag, "the tag");
  if (!std::equal(tag.begin(), tag.end(), kTag)) {
    throw Error("not moment accumulator bytes: they start with " + hex(tag) +
                ", expected the tag \"MOMACCUM\"");
  }
  const std::uint32_t version = in.u32("the layout version");
  if (version != kLayoutVersion) {
    throw Error("moment accumulator bytes of layout version " + std::to_string(version) +
                ", expected version " + std::to_string(kLayoutVersion));
  }
  const std::uint64_t states = in.u64("the number of states");
  const std::uint64_t inputs = in.u64("the number of inputs");
  if (states > kMaxChannels || inputs > kMaxChannels - states) {
    throw Error("moment accumulator bytes: " + std::to_string(states) + " states and " +
                std::to_string(inputs) + " inputs, expected at most " +
                std::to_string(kMaxChannels) + " channels");
  }
  const std::uint8_t hold = in.u8("the input hold");
  if (hold > 2) {
    throw Error("moment accumulator bytes: input hold " + std::to_string(hold) +
                ", expected 0 (sample), 1 (zero-order hold) or 2 (zero-order hold, trapezoidal)");
  }
  const std::uint64_t batches = in.u64("the number of batches");
  if (batches > std::numeric_limits<std::size_t>::max() / 4) {
    throw Error("moment accumulator bytes: " + std::to_string(batches) +
                " batches, expected at most " +
                std::to_string(std::numeric_limits<std::size_t>::max() / 4));
  }
  std::optional<MomentAccumulator> out;
  try {
    std::vector<Moment> moments(in.count(4, "moments"));
    for (std::size_t i = 0; i < moments.size(); ++i) {
      const std::string name = "moment " + std::to_string(i);
      const std::uint8_t kind = in.u8("the kind of " + name);
      if (kind > 1) {
        throw Error("moment accumulator bytes: " + name + " of kind " + std::to_string(kind) +
                    ", expected 0 (a moment) or 1 (an increment)");
      }
      std::vector<MomentFactor> factors(in.count(12, "factors of " + name));
      for (MomentFactor& f : factors) {
        f.channel = in.i32("a factor of " + name);
        f.power = in.i32("a factor of " + name);
        f.lag = in.i32("a factor of " + name);
        if (f.power < 1 || f.power > kMaxPower || f.channel < 0 || f.lag < 0) {
          throw Error("moment accumulator bytes: " + name + " has the factor channel " +
                      std::to_string(f.channel) + ", power " + std::to_string(f.power) + ", lag " +
                      std::to_string(f.lag) +
                      ", expected a channel and lag from 0 and a power from 1 to " +
                      std::to_string(kMaxPower));
        }
      }
      moments[i] = Moment(factors);
      if (kind == 1) {
        if (moments[i].is_lagged()) {
          throw Error("moment accumulator bytes: " + name +
                      " is an increment with lagged factors, expected every factor at lag 0");
        }
        moments[i] = Moment::increment_of(moments[i].at_lag(0, states + inputs));
      }
      if (moments[i].factors() != factors) {
        throw Error("moment accumulator bytes: the factors of " + name +
                    " are not in normal form (expected " + to_string(moments[i]) + ")");
      }
    }
    out.emplace(std::move(moments), states, inputs,
                hold == 0 ? InputHold::kSample : InputHold::kZeroOrderHold, batches,
                hold == 2 ? HeldRule::kTrapezoidal : HeldRule::kCubic);
  } catch (const std::invalid_argument& e) {
    throw Error(std::string("moment accumulator bytes: ") + e.what());
  }
  const std::uint64_t length = in.u64("the stretch length");
  if (!std::has_single_bit(length)) {
    throw Error("moment accumulator bytes: stretch length " + std::to_string(length) +
                ", expected a power of two");
  }
  const std::uint64_t intervals = in.u64("the number of intervals");
  const std::size_t k = out->moments_.size();
  std::vector<Stretch> stretches(in.count(8 * (k + 1), "stretches"));
  if (stretches.empty()) {
    throw Error("moment accumulator bytes: no stretches, expected at least the open one");
  }
  std::uint64_t counted = 0;
  for (Stretch& s : stretches) {
    s.intervals = in.u64("the interval count of a stretch");
    s.sums.resize(k);
    for (double& x : s.sums) x = in.f64("a sum of a stretch");
    if (s.intervals > intervals - counted) {
      throw Error("moment accumulator bytes: the stretches hold more than the " +
                  std::to_string(intervals) + " intervals counted");
    }
    counted += s.intervals;
  }
  if (counted != intervals) {
    throw Error("moment accumulator bytes: " + std::to_string(intervals) +
                " intervals counted, but the stretches hold " + std::to_string(counted));
  }
  if (in.position() != bytes.size()) {
    throw Error("moment accumulator bytes: " + count_of(bytes.size() - in.position(), "byte") +
                " after the end of the layout at byte " + std::to_string(in.position()));
  }
  out->stretch_length_ = length;
  out->intervals_ = intervals;
  out->stretches_ = std::move(stretches);
  return std::move(*out);
}

MomentEstimates estimates(const MomentAccumulator& accumulator, std::size_t batches) {
  const std::size_t k = accumulator.moments().size();
  std::vector<const MomentAccumulator::Stretch*> full;
  for (const auto& s : accumulator.stretches()) {
    if (s.intervals > 0) full.push_back(&s);
  }
  MomentEstimates out;
  out.mean.assign(k, 0.0);
  out.intervals = accumulator.intervals();
  const std::size_t b = std::max<std::size_t>(1, std::min(batches, full.size()));
  std::vector<std::vector<double>> sums(b, std::vector<double>(k, 0.0));
  std::vector<std::size_t> counts(b, 0);
  // A stretch goes to the batch its middle falls in, so that batches hold nearly equal numbers
  // of intervals.
  std::size_t before = 0;
  for (std::size_t i = 0; i < full.size(); ++i) {
    const std::size_t middle = before + full[i]->intervals / 2;
    before += full[i]->intervals;
    const std::size_t batch =
        std::min(b - 1, out.intervals > 0 ? middle * b / out.intervals : std::size_t{0});
    for (std::size_t j = 0; j < k; ++j) {
      sums[batch][j] += full[i]->sums[j];
      out.mean[j] += full[i]->sums[j];
    }
    counts[batch] += full[i]->intervals;
  }
  if (out.intervals > 0) {
    for (double& m : out.mean) m /= static_cast<double>(out.intervals);
  }
  std::vector<std::vector<double>> means;
  for (std::size_t i = 0; i < b; ++i) {
    if (counts[i] == 0) continue;
    for (double& s : sums[i]) s /= static_cast<double>(counts[i]);
    means.push_back(std::move(sums[i]));
    out.batch_intervals.push_back(counts[i]);
  }
  out.batch_means = std::move(means);
  return out;
}

}  // namespace momentid
