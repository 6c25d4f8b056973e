#pragma once

#include <compare>
#include <cstddef>
#include <initializer_list>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

namespace momentid {

// A monomial over a model's variables (Model::variables(), each of which knows its kind: a
// state, an input or a function of them), as its exponents in the order of the variables:
// `{2, 0, 1}` over (y, v, x) is y^2*x. The exponents are indexed and iterated like a vector.
//
// A monomial can also stand for the record's rate of change of itself, E[(g)'] (`rate()`): the
// moment equations keep such rates where the stationarity identities would put 0
// (DeriveOptions::rates). A rate compares after the monomial itself.
//
// Example:
//   Monomial g{1, 1, 0};          // y*v over (y, v, x)
//   Monomial r = g.as_rate();     // E[(y*v)']
//   r.rate() && r.without_rate() == g;  // true
class Monomial {
 public:
  Monomial() = default;
  Monomial(std::initializer_list<int> exponents) : exponents_(exponents) {}
  // `variables` exponents, each `exponent`.
  explicit Monomial(std::size_t variables, int exponent = 0) : exponents_(variables, exponent) {}
  explicit Monomial(std::vector<int> exponents) : exponents_(std::move(exponents)) {}
  template <std::input_iterator Iterator>
  Monomial(Iterator first, Iterator last) : exponents_(first, last) {}

  const std::vector<int>& exponents() const { return exponents_; }
  std::size_t size() const { return exponents_.size(); }
  bool empty() const { return exponents_.empty(); }
  int& operator[](std::size_t v) { return exponents_[v]; }
  int operator[](std::size_t v) const { return exponents_[v]; }
  std::vector<int>::iterator begin() { return exponents_.begin(); }
  std::vector<int>::iterator end() { return exponents_.end(); }
  std::vector<int>::const_iterator begin() const { return exponents_.begin(); }
  std::vector<int>::const_iterator end() const { return exponents_.end(); }
  // Exponents for `variables` variables, the new ones 0.
  void resize(std::size_t variables) { exponents_.resize(variables, 0); }
  // The sum of the exponents.
  int degree() const;

  bool rate() const { return rate_; }
  Monomial as_rate() const {
    Monomial out = *this;
    out.rate_ = true;
    return out;
  }
  Monomial without_rate() const {
    Monomial out = *this;
    out.rate_ = false;
    return out;
  }

  friend auto operator<=>(const Monomial&, const Monomial&) = default;
  friend bool operator==(const Monomial&, const Monomial&) = default;

 private:
  std::vector<int> exponents_;
  bool rate_ = false;
};

// One factor of a moment: channel `channel` (an index into the variables, states then inputs)
// to the power `power`, taken `lag` samples in the past, at t - lag*dt.
struct MomentFactor {
  int channel = 0;
  int power = 1;
  int lag = 0;

  friend auto operator<=>(const MomentFactor&, const MomentFactor&) = default;
};

// The expectation of a product of channel powers, each at its own time offset:
// E[x_c1(t - l1*dt)^p1 * x_c2(t - l2*dt)^p2 * ...]. The moments of the zero-lag equations have
// every factor at lag 0 (a Monomial); the lagged moment equations (DESIGN.md §6) pair a channel
// in the past with the equation at t.
//
// A Moment is kept in one normal form, so that equal moments compare equal: factors sorted by
// lag, then channel; factors of the same channel at the same lag multiplied into one; zero
// powers dropped; and every lag shifted so that the smallest is 0, since the expectation of a
// stationary process does not change when all factors are shifted by the same time. The moment
// without factors is the constant 1. Channels and powers must not be negative.
//
// Example:
//   // E[y(t - 2dt) * y(t - 2dt) * x(t - 5dt)] over (y, v, x) is E[y(t)^2 * x(t - 3dt)]:
//   Moment m({{0, 1, 2}, {2, 1, 5}, {0, 1, 2}});
//   m.degree();       // 3
//   m.max_lag();      // 3
//   m.at_lag(0, 3);   // {2, 0, 0}
//   m.at_lag(3, 3);   // {0, 0, 1}
//   Moment::from_monomial({1, 1, 0}) < m;  // a total order, for maps and sorting
class Moment {
 public:
  // The constant 1.
  Moment() = default;
  // Throws std::invalid_argument for a negative channel or power.
  explicit Moment(std::vector<MomentFactor> factors);
  // The moment of `monomial` with every factor at lag 0.
  static Moment from_monomial(const Monomial& monomial);
  // Not an expectation but the change of `monomial` across a sample interval, every factor at
  // lag 0: averaged over the intervals of a stretch of the record it is (g(end) - g(start)) /
  // intervals exactly; divided by dt, the record's E[d/dt g] (docs/uncertainty.md, "End values").
  static Moment increment_of(const Monomial& monomial);

  // In normal form (see above).
  const std::vector<MomentFactor>& factors() const { return factors_; }
  // The sum of the powers.
  int degree() const;
  // The largest lag of a factor; 0 for a moment without lags.
  int max_lag() const;
  bool is_lagged() const { return max_lag() > 0; }
  bool is_increment() const { return increment_; }
  // The exponents of the factors at `lag` over `variables` channels. Throws std::out_of_range
  // if a factor at that lag names a channel not below `variables`.
  Monomial at_lag(int lag, std::size_t variables) const;

  friend auto operator<=>(const Moment&, const Moment&) = default;
  friend bool operator==(const Moment&, const Moment&) = default;

 private:
  std::vector<MomentFactor> factors_;
  bool increment_ = false;
};

// `c1^2`, `c0(t-3)`: channel index, power above 1, and the lag when it is not 0.
std::string to_string(const MomentFactor& factor);
// The factors joined by `*`, or `1`: `c0^2*c2(t-3)`; an increment as `d(c0^2)`.
std::string to_string(const Moment& moment);

// Which channels carry the same white noise through filters, as a state formed by integration
// carries its column's: at lag s its noise and the column's are correlated, and each moment E[psi(t
// - s) F(t)] of an instrument linear in such a channel c1 is corrected by what that brings,
// kappa(s) E[(psi / c1)(t - s) dF/dc2 (t)] for each channel c2 of F with the same noise (Stein's
// lemma; kappa: covariance below).
struct SharedNoise {
  std::vector<int> source;                // per channel: the noise it carries, or -1: its own
  std::vector<std::vector<double>> taps;  // per channel with a source: the filter of its noise
  std::vector<double> variance;           // per source: its white noise's variance
  bool empty() const { return source.empty(); }
  bool shared(std::size_t c1, std::size_t c2) const {
    return c1 < source.size() && c2 < source.size() && source[c1] >= 0 && source[c1] == source[c2];
  }
  // The covariance of the noise on channel c1 at t - s with that on c2 at t (0 unless shared).
  double covariance(std::size_t c1, std::size_t c2, int s) const;
};

}  // namespace momentid
