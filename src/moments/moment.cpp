#include "momentid/moment.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace momentid {

Moment::Moment(std::vector<MomentFactor> factors) {
  for (const MomentFactor& f : factors) {
    if (f.channel < 0 || f.power < 0) {
      throw std::invalid_argument("moment factor " + to_string(f) +
                                  ": channel and power must not be negative");
    }
  }
  std::erase_if(factors, [](const MomentFactor& f) { return f.power == 0; });
  std::sort(factors.begin(), factors.end(), [](const MomentFactor& a, const MomentFactor& b) {
    return a.lag != b.lag ? a.lag < b.lag : a.channel < b.channel;
  });
  // Sums and differences in long long: a power or a lag span beyond int is refused, not wrapped.
  auto narrow = [](long long value, const char* what) {
    if (value > std::numeric_limits<int>::max()) {
      throw std::invalid_argument(std::string("moment factors: the ") + what + " " +
                                  std::to_string(value) + " is beyond int");
    }
    return static_cast<int>(value);
  };
  for (const MomentFactor& f : factors) {
    if (!factors_.empty() && factors_.back().channel == f.channel && factors_.back().lag == f.lag) {
      factors_.back().power = narrow(0LL + factors_.back().power + f.power, "power");
    } else {
      factors_.push_back(f);
    }
  }
  if (!factors_.empty()) {
    const long long first = factors_.front().lag;
    for (MomentFactor& f : factors_) f.lag = narrow(f.lag - first, "lag");
  }
}

Moment Moment::from_monomial(const Monomial& monomial) {
  std::vector<MomentFactor> factors;
  for (std::size_t v = 0; v < monomial.size(); ++v) {
    if (monomial[v] != 0) factors.push_back({static_cast<int>(v), monomial[v], 0});
  }
  return Moment(std::move(factors));
}

Moment Moment::increment_of(const Monomial& monomial) {
  Moment out = from_monomial(monomial);
  out.increment_ = true;
  return out;
}

int Monomial::degree() const {
  int sum = 0;
  for (const int e : exponents_) sum += e;
  return sum;
}

int Moment::degree() const {
  int sum = 0;
  for (const MomentFactor& f : factors_) sum += f.power;
  return sum;
}

int Moment::max_lag() const { return factors_.empty() ? 0 : factors_.back().lag; }

Monomial Moment::at_lag(int lag, std::size_t variables) const {
  Monomial out(variables, 0);
  for (const MomentFactor& f : factors_) {
    if (f.lag != lag) continue;
    if (static_cast<std::size_t>(f.channel) >= variables) {
      throw std::out_of_range("moment " + to_string(*this) + " has channel " +
                              std::to_string(f.channel) + ", expected a channel below " +
                              std::to_string(variables));
    }
    out[static_cast<std::size_t>(f.channel)] = f.power;
  }
  return out;
}

std::string to_string(const MomentFactor& factor) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, wrongly) about "c" + a temporary.
  std::string out = "c";
  out += std::to_string(factor.channel);
  if (factor.power != 1) {
    out += "^";
    out += std::to_string(factor.power);
  }
  if (factor.lag > 0) out += "(t-" + std::to_string(factor.lag) + ")";
  if (factor.lag < 0) out += "(t+" + std::to_string(-static_cast<long long>(factor.lag)) + ")";
  return out;
}

std::string to_string(const Moment& moment) {
  std::string out = moment.is_increment() ? "d(" : "";
  if (moment.factors().empty()) out += "1";
  for (std::size_t i = 0; i < moment.factors().size(); ++i) {
    if (i > 0) out += "*";
    out += to_string(moment.factors()[i]);
  }
  if (moment.is_increment()) out += ")";
  return out;
}

double SharedNoise::covariance(std::size_t c1, std::size_t c2, int s) const {
  if (!shared(c1, c2)) return 0;
  const std::vector<double>&k1 = taps[c1], &k2 = taps[c2];
  const long n1 = static_cast<long>(k1.size()), n2 = static_cast<long>(k2.size());
  double sum = 0;
  for (long i = std::max(0L, -static_cast<long>(s)); i < n1 && i + s < n2; ++i) {
    sum += k1[static_cast<std::size_t>(i)] * k2[static_cast<std::size_t>(i + s)];
  }
  return variance[static_cast<std::size_t>(source[c1])] * sum;
}

}  // namespace momentid
