#include "momentid/random.hpp"

#include <cmath>
#include <limits>

namespace momentid {
namespace {

std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

constexpr double kLn2 = 0.6931471805599453094;
constexpr double kTwoPi = 6.283185307179586477;
// Taylor coefficients (-1)^k / (2k+1)! of sin(x)/x - 1 in powers of x^2, k = 1..10, each the
// double nearest the exact value; on |x| <= pi/2 the next term is below 2e-18.
constexpr int kSineTerms = 10;
constexpr double kSin[kSineTerms] = {-1.0 / 6,
                                     1.0 / 120,
                                     -1.0 / 5040,
                                     1.0 / 362880,
                                     -1.0 / 39916800,
                                     1.0 / 6227020800,
                                     -1.0 / 1307674368000,
                                     1.0 / 355687428096000,
                                     -1.0 / 121645100408832000,
                                     1.0 / 51090942171709440000.0};

}  // namespace

PortableRandom::PortableRandom(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t state = seed ^ (0xd1b54a32d192ed03ULL * (stream + 1));
  for (auto& s : s_) s = splitmix64(state);
}

std::uint64_t PortableRandom::next() {
  const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

double PortableRandom::uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

double PortableRandom::normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  double u, v, s;
  do {
    u = 2 * uniform() - 1;
    v = 2 * uniform() - 1;
    s = u * u + v * v;
  } while (s >= 1 || s == 0);
  // sqrt is correctly rounded by IEEE-754, so it is as portable as + - * /.
  const double factor = std::sqrt(-2 * portable_log(s) / s);
  spare_ = v * factor;
  has_spare_ = true;
  return u * factor;
}

double portable_log(double x) {
  // x = m * 2^e with m in [sqrt(1/2), sqrt(2)); ln x = e ln 2 + 2 atanh((m - 1)/(m + 1)).
  int e = 0;
  double m = std::frexp(x, &e);  // exact: only changes the exponent
  if (m < 0.70710678118654752440) {
    m *= 2;
    --e;
  }
  const double r = (m - 1) / (m + 1);
  const double r2 = r * r;
  // atanh(r)/r = sum r^(2k)/(2k+1); |r| < 0.1716, so 13 terms are below 1e-20.
  double series = 1.0 / 27;
  for (int k = 12; k >= 0; --k) series = series * r2 + 1.0 / (2 * k + 1);
  return e * kLn2 + 2 * r * series;
}

double portable_exp(double x) {
  if (x < -745) return 0;  // below the smallest subnormal
  if (x > 709.8) return std::numeric_limits<double>::infinity();
  // x = k ln 2 + r with |r| <= ln2/2; exp(x) = 2^k exp(r), exp(r) by its Taylor series.
  // ln 2 split Cody-Waite style: k * kLn2High is exact for |k| < 2^20, so r keeps full precision.
  constexpr double kLn2High = 6.93147180369123816490e-01;
  constexpr double kLn2Low = 1.90821492927058770002e-10;
  const double k = std::floor(x / kLn2 + 0.5);
  const double r = (x - k * kLn2High) - k * kLn2Low;
  double sum = 1;
  double term = 1;
  for (int n = 1; n <= 20; ++n) {
    term *= r / n;
    sum += term;
  }
  return std::ldexp(sum, static_cast<int>(k));
}

double portable_cos_turns(double turns) {
  // r = distance to the nearest whole turn, in [0, 1/2]; cos(2 pi r) = -sin(2 pi (r - 1/4)) with
  // |2 pi (r - 1/4)| <= pi/2. Adding and subtracting 1.5 * 2^52 rounds to the nearest integer
  // exactly for |turns| < 2^51 without a branch or a library call; beyond, fmod is exact.
  if (!(std::abs(turns) < 0x1p51)) turns = std::fmod(turns, 1.0);
  constexpr double kRound = 0x1.8p52;
  const double r = std::abs(turns - ((turns + kRound) - kRound));
  const double x = kTwoPi * (r - 0.25);
  const double x2 = x * x;
  double series = kSin[kSineTerms - 1];
  for (int k = kSineTerms - 2; k >= 0; --k) series = kSin[k] + x2 * series;
  return -(x + x * (x2 * series));
}

}  // namespace momentid
