#pragma once

#include <cstdint>

namespace momentid {

// A random number source that gives the same sequence for the same seed on every machine and
// compiler: the xoshiro256** generator (Blackman & Vigna), seeded by expanding the 64-bit seed and
// a stream number with splitmix64; uniform doubles from the top 53 bits; standard normal values
// by Marsaglia's polar method with a logarithm computed from IEEE-754 basic operations only, so
// that no library function's rounding can change a value.
//
// Example:
//   PortableRandom random(/*seed=*/42, /*stream=*/0);
//   double z = random.normal();
class PortableRandom {
 public:
  PortableRandom(std::uint64_t seed, std::uint64_t stream);

  std::uint64_t next();
  // Uniform on [0, 1).
  double uniform();
  // Standard normal.
  double normal();

 private:
  std::uint64_t s_[4];
  double spare_ = 0;
  bool has_spare_ = false;
};

// ln(x) for finite x > 0, from +, -, *, / only (correct to about 1 ulp).
double portable_log(double x);
// exp(x) from +, -, *, / only (correct to about 1 ulp for |x| < 700).
double portable_exp(double x);
// cos(2 pi turns) for finite `turns`, from +, -, *, / and floor only (correct to a few ulp).
// The angle is given in turns so that the whole turns drop out exactly.
double portable_cos_turns(double turns);

}  // namespace momentid
