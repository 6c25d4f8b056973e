#include "moments/lag_sums.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>

#include "moments/kernel.hpp"

namespace momentid {

const ChannelStatistics* DataMoments::channel(const std::string& name) const {
  const auto found = std::find_if(channels.begin(), channels.end(),
                                  [&](const ChannelStatistics& c) { return c.name == name; });
  return found == channels.end() ? nullptr : &*found;
}

std::optional<double> ChannelStatistics::noise_fraction() const {
  if (!noise_variance || !(variance > 0)) return std::nullopt;
  return std::sqrt(std::max(0.0, *noise_variance) / variance);
}

namespace {

// Eight doubles summed lane by lane, in two Four (kernel.hpp): the additions of different lanes
// do not wait on one another. A sum's lanes are added up as ((0 + 2) + 4) + 6 and
// ((1 + 3) + 5) + 7, then the two, in that order whatever the registers.
constexpr std::size_t kLanes = 8;

struct Eight {
  Four low{}, high{};
  Eight& operator+=(const Eight& o) {
    low += o.low;
    high += o.high;
    return *this;
  }
  Eight& operator*=(const Eight& o) {
    low *= o.low;
    high *= o.high;
    return *this;
  }
};
[[gnu::always_inline]] inline Eight operator*(Eight a, const Eight& b) { return a *= b; }
[[gnu::always_inline]] inline Eight operator*(double a, const Eight& b) {
  return {a * b.low, a * b.high};
}
[[gnu::always_inline]] inline Eight operator+(const Eight& a, const Eight& b) {
  return {a.low + b.low, a.high + b.high};
}
[[gnu::always_inline]] inline Eight operator-(const Eight& a, const Eight& b) {
  return {a.low - b.low, a.high - b.high};
}

[[gnu::always_inline]] inline Eight load_eight(const double* p) {
  return {load_four(p), load_four(p + 4)};
}

[[gnu::always_inline]] inline double total(const Eight& s) {
  return (((s.low[0] + s.low[2]) + s.high[0]) + s.high[2]) +
         (((s.low[1] + s.low[3]) + s.high[1]) + s.high[3]);
}

// Over i < n: the sums of x[i] * y[i], and with Sums of x[i] and of y[i].
struct PairSums {
  double products = 0, lead = 0, lagged = 0;
};

template <bool Sums>
[[gnu::always_inline]] inline PairSums sum_pairs(const double* x, const double* y, std::size_t n) {
  Eight products{}, lead{}, lagged{};
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    const Eight xv = load_eight(x + i), yv = load_eight(y + i);
    products += xv * yv;
    if constexpr (Sums) {
      lead += xv;
      lagged += yv;
    }
  }
  PairSums out{total(products), total(lead), total(lagged)};
  for (; i < n; ++i) {
    out.products += x[i] * y[i];
    if constexpr (Sums) {
      out.lead += x[i];
      out.lagged += y[i];
    }
  }
  return out;
}

MOMENTID_KERNEL PairSums sum_own(const double* x, std::size_t n) {
  return sum_pairs<true>(x, x, n);
}
MOMENTID_KERNEL PairSums sum_lagged(const double* x, const double* y, std::size_t n) {
  return sum_pairs<true>(x, y, n);
}
MOMENTID_KERNEL double sum_products(const double* x, const double* y, std::size_t n) {
  return sum_pairs<false>(x, y, n).products;
}

// The sum over i < n of the square of the sixth difference at x[i] (x[i - 6] .. x[i]).
MOMENTID_KERNEL double sum_sixth_differences(const double* x, std::size_t n) {
  Eight sums{};
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    std::array<Eight, kNoiseDifference + 1> p;
    for (std::size_t j = 0; j <= kNoiseDifference; ++j) p[j] = load_eight(x + i - j);
    const Eight d = p[0] - 6 * p[1] + 15 * p[2] - 20 * p[3] + 15 * p[4] - 6 * p[5] + p[6];
    sums += d * d;
  }
  double out = total(sums);
  for (; i < n; ++i) {
    const double d = sixth_difference(x + i);
    out += d * d;
  }
  return out;
}

// The sum of x[i] over first <= i < last (a few terms).
double range_sum(const double* x, std::ptrdiff_t first, std::ptrdiff_t last) {
  double out = 0;
  for (std::ptrdiff_t i = first; i < last; ++i) out += x[i];
  return out;
}

// The sum over i < n of w[i] times the product of the columns `factors` (`count` of them, each
// kPointGroup values from `table`) at i.
MOMENTID_KERNEL double weighted_sum(const double* w, const std::uint32_t* factors,
                                    std::size_t count, const double* table, std::size_t n) {
  Eight sums{};
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    Eight p = load_eight(w + i);
    for (std::size_t f = 0; f < count; ++f)
      p *= load_eight(table + factors[f] * LagSums::kPointGroup + i);
    sums += p;
  }
  double out = total(sums);
  for (; i < n; ++i) {
    double p = w[i];
    for (std::size_t f = 0; f < count; ++f) p *= table[factors[f] * LagSums::kPointGroup + i];
    out += p;
  }
  return out;
}

// x[r] = values[r * stride] - offset for r < n; returns the largest |values[r * stride]|.
MOMENTID_KERNEL double fill_values(double* x, const double* values, std::size_t stride,
                                   std::size_t n, double offset) {
  std::array<double, kLanes> top{};
  std::size_t r = 0;
  for (; r + kLanes <= n; r += kLanes) {
    for (std::size_t j = 0; j < kLanes; ++j) {
      const double v = values[(r + j) * stride];
      top[j] = std::max(top[j], std::abs(v));
      x[r + j] = v - offset;
    }
  }
  for (; r < n; ++r) {
    const double v = values[r * stride];
    top[0] = std::max(top[0], std::abs(v));
    x[r] = v - offset;
  }
  return *std::max_element(top.begin(), top.end());
}

// The sums of a block x[0, n) of one channel whose six values before it are the run's, in one
// sweep: sum_own's, sum_products' at lags 1 .. Lags and sum_sixth_differences', each over the
// lanes its own kernel keeps, so that they are the same numbers.
constexpr std::size_t kSweptLags = 4;
struct BlockSums {
  PairSums own;
  std::array<double, kSweptLags> lagged{};
  double sixth = 0;
};

template <std::size_t Lags>
[[gnu::always_inline]] inline BlockSums sweep(const double* x, std::size_t n) {
  static_assert(Lags <= kNoiseDifference);
  Eight products{}, lead{}, sixth{};
  std::array<Eight, Lags> lagged{};
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    std::array<Eight, kNoiseDifference + 1> p;
    for (std::size_t j = 0; j <= kNoiseDifference; ++j) p[j] = load_eight(x + i - j);
    products += p[0] * p[0];
    lead += p[0];
    for (std::size_t l = 1; l <= Lags; ++l) lagged[l - 1] += p[0] * p[l];
    const Eight d = p[0] - 6 * p[1] + 15 * p[2] - 20 * p[3] + 15 * p[4] - 6 * p[5] + p[6];
    sixth += d * d;
  }
  BlockSums out{{total(products), total(lead), total(lead)}, {}, total(sixth)};
  for (std::size_t l = 1; l <= Lags; ++l) out.lagged[l - 1] = total(lagged[l - 1]);
  for (; i < n; ++i) {
    out.own.products += x[i] * x[i];
    out.own.lead += x[i];
    for (std::size_t l = 1; l <= Lags; ++l) out.lagged[l - 1] += x[i] * x[i - l];
    const double d = sixth_difference(x + i);
    out.sixth += d * d;
  }
  out.own.lagged = out.own.lead;
  return out;
}

MOMENTID_KERNEL BlockSums sweep_block(const double* x, std::size_t n, std::size_t lags) {
  switch (lags) {
    case 1:
      return sweep<1>(x, n);
    case 2:
      return sweep<2>(x, n);
    case 3:
      return sweep<3>(x, n);
    default:
      return sweep<kSweptLags>(x, n);
  }
}

}  // namespace

LagSums::LagSums(std::size_t channels, std::size_t lags, const std::vector<Monomial>& points)
    : channels_(channels),
      lags_(lags),
      reach_(std::max(lags, kNoiseDifference)),
      history_(reach_ * channels, 0.0),
      sum_(channels, 0.0),
      sum_squares_(channels, 0.0),
      products_(lags * channels, 0.0),
      differences_(channels, 0.0),
      lead_(lags * channels, 0.0),
      lagged_(lags * channels, 0.0),
      pairs_(lags, 0),
      largest_(channels, 0.0),
      largest_row_(channels, 0) {
  if (points.empty()) return;
  // The power table: powers 0 .. the largest exponent of each channel.
  power_at_.assign(channels + 1, 0);
  for (std::size_t c = 0; c < channels; ++c) {
    int top = 0;
    for (const Monomial& m : points) top = std::max(top, m[c]);
    power_at_[c + 1] = power_at_[c] + static_cast<std::size_t>(top) + 1;
    if (top > 0) point_channels_.push_back(c);
  }
  powers_.assign(power_at_[channels] * kPointGroup, 1.0);
  point_weights_.assign(kPointGroup, 0.0);
  // Each distinct monomial once (products of pairs repeat): the sums are the distinct ones'.
  point_factors_.push_back(0);
  std::map<Monomial, std::size_t> distinct;
  for (const Monomial& m : points) {
    const auto [at, added] = distinct.try_emplace(m, distinct.size());
    point_index_.push_back(at->second);
    if (!added) continue;
    for (std::size_t c = 0; c < channels; ++c) {
      if (m[c] > 0) factors_.push_back(static_cast<std::uint32_t>(power_at_[c]) + m[c]);
    }
    point_factors_.push_back(static_cast<std::uint32_t>(factors_.size()));
  }
  point_sums_.assign(distinct.size(), 0.0);
}

void LagSums::add_history(const double* rows, std::size_t count) {
  // Remembered as read: the offset is not known before the shard's first row.
  for (std::size_t c = 0; c < channels_; ++c) {
    fill_column(c, rows, count, 0.0);
    keep_history(c);
  }
  filled_ += count;
}

void LagSums::add(const double* rows, std::size_t count) {
  if (count == 0) return;
  if (count_ == 0) {
    offset_.assign(rows, rows + channels_);
    // The rows before the shard, remembered as read, less the offset now known.
    for (std::size_t k = 0; k < history_.size(); ++k) history_[k] -= offset_[k / reach_];
  }
  // The first row of the block that lag l pairs: the run's (l + 1)-th.
  const auto first_paired = [&](std::size_t l) {
    return std::min(l > filled_ ? l - filled_ : 0, count);
  };
  // Past the run's first rows every sum starts at the block's first row: one sweep (sweep_block)
  // takes them all.
  const bool swept = filled_ >= reach_ && lags_ <= kSweptLags && count >= 2 * lags_;
  for (std::size_t c = 0; c < channels_; ++c) {
    const double top = fill_column(c, rows, count, offset_[c]);
    double* const x = column_.data() + reach_;  // the block's values less the offset
    if (top > largest_[c]) {
      largest_[c] = top;
      std::size_t r = 0;
      while (std::abs(rows[r * channels_ + c]) != top) ++r;
      largest_row_[c] = count_ + r;
    }
    const BlockSums block = swept ? sweep_block(x, count, lags_) : BlockSums{sum_own(x, count)};
    const PairSums& own = block.own;
    sum_[c] += own.lead;
    sum_squares_[c] += own.products;
    // Lag l pairs each row with the one l rows earlier in the run, history included. The sums
    // of the values paired are the block's sum less the few rows at its ends that lag l leaves
    // out, with the history's rows it takes.
    for (std::size_t l = 1; l <= lags_; ++l) {
      const std::size_t first = first_paired(l);
      const std::size_t i = (l - 1) * channels_ + c;
      if (count < 2 * l) {
        const PairSums pairs = sum_lagged(x + first, x + first - l, count - first);
        products_[i] += pairs.products;
        lead_[i] += pairs.lead;
        lagged_[i] += pairs.lagged;
        continue;
      }
      const auto lag = static_cast<std::ptrdiff_t>(l), begin = static_cast<std::ptrdiff_t>(first),
                 end = static_cast<std::ptrdiff_t>(count);
      products_[i] +=
          swept ? block.lagged[l - 1] : sum_products(x + first, x + first - l, count - first);
      lead_[i] += own.lead - range_sum(x, 0, begin);
      lagged_[i] += own.lead - range_sum(x, end - lag, end) + range_sum(x, begin - lag, 0);
    }
    const std::size_t first = first_paired(kNoiseDifference);
    differences_[c] += swept ? block.sixth : sum_sixth_differences(x + first, count - first);
    keep_history(c);
  }
  for (std::size_t l = 1; l <= lags_; ++l) pairs_[l - 1] += count - first_paired(l);
  differenced_ += count - first_paired(kNoiseDifference);
  filled_ += count;
  count_ += count;
  add_points(rows, count);
}

namespace {

// The stride of the point sums at the `position`-th row a shard adds: every row of the first
// kPointRows, then every 2nd up to twice as many, every 4th up to four times as many, and so on to
// every kPointStride-th, so that a short record gives every row and a long one a small fraction
// of the work. Each row sampled stands for `stride` rows.
constexpr std::size_t kPointRows = std::size_t{1} << 12, kPointStride = 32;
std::size_t point_stride(std::size_t position) {
  std::size_t stride = 1;
  while (stride < kPointStride && position >= stride * kPointRows) stride *= 2;
  return stride;
}

}  // namespace

void LagSums::add_points(const double* rows, std::size_t count) {
  if (point_sums_.empty()) return;
  const std::size_t first = count_ - count;  // the rows added before these
  const auto column = [&](std::size_t j) { return powers_.data() + j * kPointGroup; };
  std::size_t r = point_skip_;
  while (r < count) {
    // Up to kPointGroup rows sampled, a column each: their weights, each channel's value.
    std::size_t n = 0;
    for (std::size_t stride = point_stride(first + r); r < count && n < kPointGroup;
         r += stride, stride = point_stride(first + r), ++n) {
      point_weights_[n] = static_cast<double>(stride);
      for (const std::size_t c : point_channels_)
        column(power_at_[c] + 1)[n] = rows[r * channels_ + c];
      point_rows_ += stride;
    }
    // The higher powers, then each monomial's weighted sum along the columns of its factors.
    for (const std::size_t c : point_channels_) {
      const double* value = column(power_at_[c] + 1);
      for (std::size_t j = power_at_[c] + 2; j < power_at_[c + 1]; ++j) {
        const double* lower = column(j - 1);
        double* power = column(j);
        for (std::size_t i = 0; i < n; ++i) power[i] = lower[i] * value[i];
      }
    }
    for (std::size_t k = 0; k < point_sums_.size(); ++k) {
      point_sums_[k] += weighted_sum(point_weights_.data(), factors_.data() + point_factors_[k],
                                     point_factors_[k + 1] - point_factors_[k], powers_.data(), n);
    }
  }
  point_skip_ = r - count;
}

double LagSums::fill_column(std::size_t c, const double* rows, std::size_t count, double offset) {
  column_.resize(reach_ + count);
  std::copy_n(history_.begin() + static_cast<std::ptrdiff_t>(c * reach_), reach_, column_.begin());
  return fill_values(column_.data() + reach_, rows + c, channels_, count, offset);
}

void LagSums::keep_history(std::size_t c) {
  std::copy(column_.end() - static_cast<std::ptrdiff_t>(reach_), column_.end(),
            history_.begin() + static_cast<std::ptrdiff_t>(c * reach_));
}

void LagSums::save(ByteWriter& out) const {
  out.u64(count_);
  for (const auto* v :
       {&offset_, &sum_, &sum_squares_, &products_, &lead_, &lagged_, &differences_}) {
    out.u64(v->size());
    for (double x : *v) out.f64(x);
  }
  for (std::size_t p : pairs_) out.u64(p);
  out.u64(differenced_);
  for (std::size_t c = 0; c < channels_; ++c) {
    out.f64(largest_[c]);
    out.u64(largest_row_[c]);
  }
  out.u64(point_index_.size());
  for (std::size_t k : point_index_) out.u64(k);
  out.u64(point_sums_.size());
  out.u64(point_parts_.size());
  for (std::size_t p = 0; p <= point_parts_.size(); ++p) {
    const bool own = p == 0;
    out.u64(own ? point_rows_ : point_parts_[p - 1].rows);
    for (double x : own ? point_sums_ : point_parts_[p - 1].sums) out.f64(x);
  }
}

LagSums LagSums::load(ByteReader& in, std::size_t channels, std::size_t lags) {
  LagSums out(channels, lags);
  out.count_ = in.u64("the row count of the channel sums");
  for (auto* v : {&out.offset_, &out.sum_, &out.sum_squares_, &out.products_, &out.lead_,
                  &out.lagged_, &out.differences_}) {
    const std::uint64_t n = in.u64("a count of channel sums");
    if (n != v->size() && !(v == &out.offset_ && n == channels)) {
      throw Error("the result of another process does not match this one's channels");
    }
    v->resize(n);
    for (double& x : *v) x = in.f64("a channel sum");
  }
  for (std::size_t& p : out.pairs_) p = in.u64("a count of pairs");
  out.differenced_ = in.u64("a count of differences");
  for (std::size_t c = 0; c < channels; ++c) {
    out.largest_[c] = in.f64("a channel's largest value");
    out.largest_row_[c] = in.u64("the row of a channel's largest value");
  }
  out.point_index_.resize(in.count(8, "point moments"));
  for (std::size_t& k : out.point_index_) k = in.u64("a point moment's sum");
  const std::size_t distinct = in.count(8, "point sums");
  out.point_parts_.resize(in.count(8, "parts of the point sums"));
  for (std::size_t p = 0; p <= out.point_parts_.size(); ++p) {
    PointPart part;
    part.rows = in.u64("the row count of point sums");
    part.sums.resize(distinct);
    for (double& x : part.sums) x = in.f64("a point sum");
    if (p == 0) {
      out.point_rows_ = part.rows;
      out.point_sums_ = std::move(part.sums);
    } else {
      out.point_parts_[p - 1] = std::move(part);
    }
  }
  if (std::any_of(out.point_index_.begin(), out.point_index_.end(),
                  [&](std::size_t k) { return k >= out.point_sums_.size(); })) {
    throw Error("the result of another process does not match this one's point sums");
  }
  return out;
}

void LagSums::merge(const LagSums& other) {
  if (other.count_ == 0) return;
  if (count_ == 0) {
    *this = other;
    return;
  }
  if (other.point_sums_.size() != point_sums_.size() || other.point_index_ != point_index_) {
    throw Error("the result of another process does not match this one's point sums");
  }
  point_parts_.push_back({other.point_rows_, other.point_sums_});
  point_parts_.insert(point_parts_.end(), other.point_parts_.begin(), other.point_parts_.end());
  for (std::size_t c = 0; c < channels_; ++c) {
    if (other.largest_[c] > largest_[c]) {
      largest_[c] = other.largest_[c];
      largest_row_[c] = count_ + other.largest_row_[c];
    }
    // other's values less this offset: x - o = (x - o_other) - d.
    const double d = offset_[c] - other.offset_[c];
    const auto n = static_cast<double>(other.count_);
    sum_[c] += other.sum_[c] - n * d;
    sum_squares_[c] += other.sum_squares_[c] - 2 * d * other.sum_[c] + n * d * d;
    differences_[c] += other.differences_[c];
    for (std::size_t l = 0; l < lags_; ++l) {
      const std::size_t i = l * channels_ + c;
      const auto p = static_cast<double>(other.pairs_[l]);
      products_[i] += other.products_[i] - d * (other.lead_[i] + other.lagged_[i]) + p * d * d;
      lead_[i] += other.lead_[i] - p * d;
      lagged_[i] += other.lagged_[i] - p * d;
    }
  }
  for (std::size_t l = 0; l < lags_; ++l) pairs_[l] += other.pairs_[l];
  differenced_ += other.differenced_;
  count_ += other.count_;
}

ChannelStatistics LagSums::statistics(std::size_t c, bool held) const {
  ChannelStatistics s;
  const double n = static_cast<double>(count_);
  const double shifted_mean = sum_[c] / n;
  s.mean = offset_[c] + shifted_mean;
  s.variance = sum_squares_[c] / n - shifted_mean * shifted_mean;
  s.largest = largest_[c];
  s.largest_row = largest_row_[c];
  s.correlation_time = lags_ + 1;
  // The lag-l covariance about the record's mean over the pairs that lag has. The values
  // paired are not all the values (a run's first l rows lead no pair, its last l are lagged by
  // none), so the pairs' own sums enter: on short runs their means are not the record's.
  for (std::size_t l = 0; l < lags_; ++l) {
    const std::size_t i = l * channels_ + c;
    const auto p = static_cast<double>(pairs_[l]);
    const double rho = pairs_[l] > 0 && s.variance > 0
                           ? ((products_[i] - shifted_mean * (lead_[i] + lagged_[i])) / p +
                              shifted_mean * shifted_mean) /
                                 s.variance
                           : std::nan("");
    s.autocorrelation.push_back(rho);
    if (s.correlation_time == lags_ + 1 && rho < std::exp(-1.0)) s.correlation_time = l + 1;
  }
  if (held && lags_ >= 4 && s.variance > 0) {
    s.noise_variance = s.variance * (1 - held_lag_zero(s.autocorrelation));
  } else if (!held && differenced_ > 0) {
    s.noise_variance = differences_[c] / static_cast<double>(differenced_) / kSixthDifferenceGain;
  }
  return s;
}

std::vector<double> LagSums::point_means() const {
  std::vector<double> sums = point_sums_;
  std::size_t rows = point_rows_;
  for (const PointPart& part : point_parts_) {
    for (std::size_t k = 0; k < sums.size(); ++k) sums[k] += part.sums[k];
    rows += part.rows;
  }
  std::vector<double> out(point_index_.size(), std::nan(""));
  if (rows == 0) return out;
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k] = sums[point_index_[k]] / static_cast<double>(rows);
  }
  return out;
}

double held_lag_zero(const std::vector<double>& rho) {
  return 1.92 * rho[0] - 1.44 * rho[1] + 0.64 * rho[2] - 0.12 * rho[3];
}

}  // namespace momentid
