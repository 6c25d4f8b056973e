#include "moments/accumulator.hpp"

#include <algorithm>

namespace momentid {

MomentAccumulator::MomentAccumulator(std::vector<Monomial> moments, std::size_t states,
                                     std::size_t inputs, InputHold hold, std::size_t batches)
    : moments_(std::move(moments)),
      states_(states),
      inputs_(inputs),
      hold_(hold),
      max_stretches_(4 * std::max<std::size_t>(batches, 2)) {
  const std::size_t variables = states_ + inputs_;
  max_power_.assign(variables, 1);
  for (const Monomial& m : moments_) {
    for (std::size_t v = 0; v < variables; ++v) max_power_[v] = std::max(max_power_[v], m[v]);
  }
  std::size_t offset = 0;
  for (int p : max_power_) {
    power_offset_.push_back(offset);
    offset += static_cast<std::size_t>(p) + 1;
  }
  powers_.assign(offset, 1.0);
  for (const Monomial& m : moments_) {
    std::vector<std::size_t> state, input;
    for (std::size_t v = 0; v < variables; ++v) {
      if (m[v] == 0) continue;
      (v < states_ ? state : input).push_back(power_offset_[v] + static_cast<std::size_t>(m[v]));
    }
    state_factors_.push_back(std::move(state));
    input_factors_.push_back(std::move(input));
  }
  const std::size_t k = moments_.size();
  state_part_.assign(k, 0);
  input_part_.assign(k, 0);
  previous_state_part_.assign(k, 0);
  previous_input_part_.assign(k, 0);
  stretches_.push_back({std::vector<double>(k, 0.0), 0});
}

void MomentAccumulator::start_run() { has_previous_ = false; }

void MomentAccumulator::add(const double* rows, std::size_t count) {
  const std::size_t variables = states_ + inputs_;
  const std::size_t k = moments_.size();
  for (std::size_t r = 0; r < count; ++r) {
    const double* row = rows + r * variables;
    for (std::size_t v = 0; v < variables; ++v) {
      double* p = &powers_[power_offset_[v]];
      p[1] = row[v];
      for (int e = 2; e <= max_power_[v]; ++e) p[e] = p[e - 1] * row[v];
    }
    for (std::size_t i = 0; i < k; ++i) {
      double s = 1, u = 1;
      for (std::size_t f : state_factors_[i]) s *= powers_[f];
      for (std::size_t f : input_factors_[i]) u *= powers_[f];
      state_part_[i] = s;
      input_part_[i] = u;
    }
    if (has_previous_) {
      Stretch& stretch = stretches_.back();
      double* sums = stretch.sums.data();
      for (std::size_t i = 0; i < k; ++i) {
        if (hold_ == InputHold::kZeroOrderHold && !input_factors_[i].empty()) {
          // The input of the earlier row is held over the whole interval.
          sums[i] += previous_input_part_[i] * 0.5 * (previous_state_part_[i] + state_part_[i]);
        } else {
          sums[i] += 0.5 * (previous_state_part_[i] * previous_input_part_[i] +
                            state_part_[i] * input_part_[i]);
        }
      }
      ++stretch.intervals;
      ++intervals_;
      if (stretch.intervals == stretch_length_) {
        stretches_.push_back({std::vector<double>(k, 0.0), 0});
        if (stretches_.size() > max_stretches_) compact();
      }
    }
    previous_state_part_.swap(state_part_);
    previous_input_part_.swap(input_part_);
    has_previous_ = true;
  }
}

// Halves the number of stretches by adding neighbours; the open (last) stretch stays last.
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

void MomentAccumulator::merge(const MomentAccumulator& other) {
  if (stretches_.back().intervals == 0) stretches_.pop_back();
  for (const Stretch& s : other.stretches_) {
    if (s.intervals > 0) stretches_.push_back(s);
  }
  intervals_ += other.intervals_;
  stretches_.push_back({std::vector<double>(moments_.size(), 0.0), 0});
  while (stretches_.size() > max_stretches_) compact();
  has_previous_ = false;
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
  const std::size_t b = std::min(batches, full.size());
  std::vector<std::vector<double>> sums(b, std::vector<double>(k, 0.0));
  std::vector<std::size_t> counts(b, 0);
  for (std::size_t i = 0; i < full.size(); ++i) {
    const std::size_t batch = i * b / full.size();
    for (std::size_t j = 0; j < k; ++j) {
      sums[batch][j] += full[i]->sums[j];
      out.mean[j] += full[i]->sums[j];
    }
    counts[batch] += full[i]->intervals;
  }
  if (out.intervals > 0) {
    for (double& m : out.mean) m /= static_cast<double>(out.intervals);
  }
  for (std::size_t i = 0; i < b; ++i) {
    for (double& s : sums[i]) s /= static_cast<double>(counts[i]);
  }
  out.batch_means = std::move(sums);
  return out;
}

std::vector<std::vector<double>> MomentEstimates::covariance() const {
  const std::size_t k = mean.size(), b = batch_means.size();
  std::vector<std::vector<double>> c(k, std::vector<double>(k, 0.0));
  if (b < 2) return c;
  std::vector<double> center(k, 0.0);
  for (const auto& m : batch_means) {
    for (std::size_t i = 0; i < k; ++i) center[i] += m[i] / static_cast<double>(b);
  }
  for (const auto& m : batch_means) {
    for (std::size_t i = 0; i < k; ++i) {
      for (std::size_t j = 0; j < k; ++j) c[i][j] += (m[i] - center[i]) * (m[j] - center[j]);
    }
  }
  const double scale = 1.0 / (static_cast<double>(b - 1) * static_cast<double>(b));
  for (auto& row : c) {
    for (double& x : row) x *= scale;
  }
  return c;
}

}  // namespace momentid
