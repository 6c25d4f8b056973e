#include "momentid/accumulator.hpp"

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
  // Each moment's state factors, then its input factors, as indices into the power table.
  first_factor_.push_back(0);
  for (std::size_t i = 0; i < moments_.size(); ++i) {
    const Monomial& m = moments_[i];
    bool has_input = false;
    for (std::size_t v = 0; v < states_; ++v) {
      if (m[v] != 0) factors_.push_back(power_offset_[v] + static_cast<std::size_t>(m[v]));
    }
    first_factor_.push_back(factors_.size());
    for (std::size_t v = states_; v < variables; ++v) {
      if (m[v] == 0) continue;
      factors_.push_back(power_offset_[v] + static_cast<std::size_t>(m[v]));
      has_input = true;
    }
    first_factor_.push_back(factors_.size());
    (hold_ == InputHold::kZeroOrderHold && has_input ? held_ : plain_).push_back(i);
  }
  const std::size_t k = moments_.size();
  state_ring_.assign(4 * k, 0.0);
  input_ring_.assign(4 * k, 0.0);
  stretches_.push_back({std::vector<double>(k, 0.0), 0});
}

void MomentAccumulator::start_run() {
  finish_run();
  run_rows_ = 0;
}

void MomentAccumulator::finish() { finish_run(); }

// The last interval of the run, which has no row after it.
void MomentAccumulator::finish_run() {
  if (run_rows_ >= 2) close_interval(run_rows_ - 2);
  run_rows_ = 0;
}

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
    double* state = state_ring_.data() + (run_rows_ % 4) * k;
    double* input = input_ring_.data() + (run_rows_ % 4) * k;
    const std::size_t* factors = factors_.data();
    const std::size_t* first = first_factor_.data();
    const double* powers = powers_.data();
    for (std::size_t i = 0; i < k; ++i) {
      double g = 1, h = 1;
      for (std::size_t f = first[2 * i]; f < first[2 * i + 1]; ++f) g *= powers[factors[f]];
      for (std::size_t f = first[2 * i + 1]; f < first[2 * i + 2]; ++f) h *= powers[factors[f]];
      state[i] = g;
      input[i] = h;
    }
    ++run_rows_;
    // With rows up to m = run_rows_ - 1 known, the interval [m - 2, m - 1] can be closed.
    if (run_rows_ >= 3) close_interval(run_rows_ - 3);
  }
}

// Adds the average over the interval between rows n and n + 1 of the run. A product with a held
// input is u[n] times the integral of g(y) over the interval; the trapezoidal rule would leave an
// error -dt^2/12 * E[u g''] that does not average out, so g is integrated by the cubic through
// the rows n - 1 .. n + 2 (one-sided at the ends of a run). Where g has a kink at every row (a
// state whose derivative contains the held input) an O(dt^2) remainder stays, smaller than the
// trapezoidal rule's: this is the bias of coarse sampling that `identify` warns about. Other
// products are continuous across rows, and the trapezoidal rule's error then only accumulates
// at the ends of a run.
void MomentAccumulator::close_interval(std::size_t n) {
  const std::size_t k = moments_.size();
  const std::size_t rows = run_rows_;
  auto state = [&](std::size_t row) { return state_ring_.data() + (row % 4) * k; };
  auto input = [&](std::size_t row) { return input_ring_.data() + (row % 4) * k; };
  const double* g0 = state(n);
  const double* g1 = state(n + 1);
  const double* h0 = input(n);
  const double* h1 = input(n + 1);
  // Weights of g at rows n - 1, n, n + 1, n + 2 for the integral over [n, n + 1] / dt.
  double w[4] = {0, 0.5, 0.5, 0};
  if (n >= 1 && n + 2 < rows) {
    w[0] = -1.0 / 24;
    w[1] = 13.0 / 24;
    w[2] = 13.0 / 24;
    w[3] = -1.0 / 24;
  } else if (n + 2 < rows) {  // first interval of the run
    w[1] = 5.0 / 12;
    w[2] = 8.0 / 12;
    w[3] = -1.0 / 12;
  } else if (n >= 1) {  // last interval of the run
    w[0] = -1.0 / 12;
    w[1] = 8.0 / 12;
    w[2] = 5.0 / 12;
  }
  const double* gm = n >= 1 ? state(n - 1) : g0;
  const double* g2 = n + 2 < rows ? state(n + 2) : g1;
  Stretch& stretch = stretches_.back();
  double* sums = stretch.sums.data();
  for (std::size_t i : held_) {
    sums[i] += h0[i] * (w[0] * gm[i] + w[1] * g0[i] + w[2] * g1[i] + w[3] * g2[i]);
  }
  for (std::size_t i : plain_) sums[i] += 0.5 * (g0[i] * h0[i] + g1[i] * h1[i]);
  ++stretch.intervals;
  ++intervals_;
  if (stretch.intervals >= stretch_length_) {
    stretches_.push_back({std::vector<double>(k, 0.0), 0});
    if (stretches_.size() > max_stretches_) compact();
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
  finish_run();
  if (stretches_.back().intervals == 0) stretches_.pop_back();
  for (const Stretch& s : other.stretches_) {
    if (s.intervals > 0) stretches_.push_back(s);
  }
  intervals_ += other.intervals_;
  stretches_.push_back({std::vector<double>(moments_.size(), 0.0), 0});
  while (stretches_.size() > max_stretches_) compact();
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
  }
  out.batch_means = std::move(means);
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
