#include "moments/lag_sums.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace momentid {

std::optional<double> ChannelStatistics::noise_fraction() const {
  if (!noise_variance || !(variance > 0)) return std::nullopt;
  return std::sqrt(std::max(0.0, *noise_variance) / variance);
}

LagSums::LagSums(std::size_t channels, std::size_t lags)
    : channels_(channels),
      lags_(lags),
      history_(2 * lags * channels, 0.0),
      repeated_(lags * channels, 0.0),
      sum_(channels, 0.0),
      sum_squares_(channels, 0.0),
      products_(lags * channels, 0.0),
      lead_(lags * channels, 0.0),
      lagged_(lags * channels, 0.0),
      pairs_(lags, 0),
      largest_(channels, 0.0),
      largest_row_(channels, 0) {}

void LagSums::add_history(const double* rows, std::size_t count) {
  for (std::size_t r = 0; r < count; ++r) remember(rows + r * channels_);
}

void LagSums::add(const double* rows, std::size_t count) {
  for (std::size_t r = 0; r < count; ++r) {
    const double* const row = rows + r * channels_;
    if (count_ == 0) {
      offset_.assign(row, row + channels_);
      // The rows before the shard, remembered as read, less the offset now known.
      for (std::size_t k = 0; k < history_.size(); ++k) history_[k] -= offset_[k % channels_];
    }
    for (std::size_t c = 0; c < channels_; ++c) {
      if (std::abs(row[c]) > largest_[c]) {
        largest_[c] = std::abs(row[c]);
        largest_row_[c] = count_;
      }
      const double x = row[c] - offset_[c];
      sum_[c] += x;
      sum_squares_[c] += x * x;
      for (std::size_t l = 0; l < lags_; ++l) repeated_[l * channels_ + c] = x;
    }
    // The previous rows, newest first, against this one: every lag and channel in one sweep.
    const double* past = &history_[head_ * channels_];
    const std::size_t paired = std::min(filled_, lags_) * channels_;
    for (std::size_t k = 0; k < paired; ++k) {
      products_[k] += repeated_[k] * past[k];
      lead_[k] += repeated_[k];
      lagged_[k] += past[k];
    }
    for (std::size_t l = 0; l < std::min(filled_, lags_); ++l) ++pairs_[l];
    remember(repeated_.data());
    ++count_;
  }
}

void LagSums::save(ByteWriter& out) const {
  out.u64(count_);
  for (const auto* v : {&offset_, &sum_, &sum_squares_, &products_, &lead_, &lagged_}) {
    out.u64(v->size());
    for (double x : *v) out.f64(x);
  }
  for (std::size_t p : pairs_) out.u64(p);
  for (std::size_t c = 0; c < channels_; ++c) {
    out.f64(largest_[c]);
    out.u64(largest_row_[c]);
  }
}

LagSums LagSums::load(ByteReader& in, std::size_t channels, std::size_t lags) {
  LagSums out(channels, lags);
  out.count_ = in.u64("the row count of the channel sums");
  for (auto* v :
       {&out.offset_, &out.sum_, &out.sum_squares_, &out.products_, &out.lead_, &out.lagged_}) {
    const std::uint64_t n = in.u64("a count of channel sums");
    if (n != v->size() && !(v == &out.offset_ && n == channels)) {
      throw Error("the result of another process does not match this one's channels");
    }
    v->resize(n);
    for (double& x : *v) x = in.f64("a channel sum");
  }
  for (std::size_t& p : out.pairs_) p = in.u64("a count of pairs");
  for (std::size_t c = 0; c < channels; ++c) {
    out.largest_[c] = in.f64("a channel's largest value");
    out.largest_row_[c] = in.u64("the row of a channel's largest value");
  }
  return out;
}

void LagSums::merge(const LagSums& other) {
  if (other.count_ == 0) return;
  if (count_ == 0) {
    *this = other;
    return;
  }
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
    for (std::size_t l = 0; l < lags_; ++l) {
      const std::size_t i = l * channels_ + c;
      const auto p = static_cast<double>(other.pairs_[l]);
      products_[i] += other.products_[i] - d * (other.lead_[i] + other.lagged_[i]) + p * d * d;
      lead_[i] += other.lead_[i] - p * d;
      lagged_[i] += other.lagged_[i] - p * d;
    }
  }
  for (std::size_t l = 0; l < lags_; ++l) pairs_[l] += other.pairs_[l];
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
  if (lags_ >= 4 && s.variance > 0) {
    s.noise_variance = s.variance * (1 - smooth_lag_zero(s.autocorrelation, held));
  }
  return s;
}

void LagSums::remember(const double* row) {
  if (lags_ > 0) {
    head_ = head_ == 0 ? lags_ - 1 : head_ - 1;
    std::copy(row, row + channels_, &history_[head_ * channels_]);
    std::copy(row, row + channels_, &history_[(head_ + lags_) * channels_]);
  }
  ++filled_;
}

double smooth_lag_zero(const std::vector<double>& rho, bool held) {
  if (held) return 1.92 * rho[0] - 1.44 * rho[1] + 0.64 * rho[2] - 0.12 * rho[3];
  // Lagrange's extrapolation to s^2 = 0 through s^2 = 1, 4, 9, 16.
  return 1.6 * rho[0] - 0.8 * rho[1] + 1.6 / 7 * rho[2] - 0.2 / 7 * rho[3];
}

}  // namespace momentid
