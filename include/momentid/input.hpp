#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "momentid/random.hpp"

namespace momentid {

// A stationary Gaussian input process, sampled once per integration step and held constant over
// the step (zero-order hold). Written `KIND:key=value,...`:
//
//   ma:K=10,w=0.1          moving average x_n = sum_{i<K} w_i v_{n-i} of white noise v, the
//                          report's input; K equal weights w, or `weights=[0.3,0.4,0.3]`
//   ou:tau=0.5             first-order filtered noise with correlation time tau (seconds):
//                          x_{n+1} = a x_n + sqrt(1 - a^2) e_n, a = exp(-dt/tau)
//   white                  a new independent value every step
//
// `sigma=` and `mean=` set the standard deviation and mean: for `ma` those of the white noise v
// that is averaged (as in the report's program), for `ou` and `white` those of x itself.
// Defaults: sigma=1, mean=0. The default process is `ma:K=10,w=0.1`.
struct InputSpec {
  enum class Kind { kMovingAverage, kOrnsteinUhlenbeck, kWhite };
  Kind kind = Kind::kMovingAverage;
  std::vector<double> weights = std::vector<double>(10, 0.1);
  double tau = 1;
  double sigma = 1;
  double mean = 0;

  // Parses the text form above; throws UsageError naming `option` and what is wrong.
  static InputSpec parse(const std::string& text, const std::string& option);
  // The canonical text form, e.g. `ma:K=10,w=0.1,sigma=1,mean=0`.
  std::string text() const;
};

// Generates one input's samples.
class InputProcess {
 public:
  InputProcess(const InputSpec& spec, double dt, std::uint64_t seed, std::uint64_t stream);
  double next();

 private:
  InputSpec spec_;
  PortableRandom random_;
  std::vector<double> history_;  // moving average: the last K noise values, newest at `head_`
  std::size_t head_ = 0;
  double state_ = 0;  // Ornstein-Uhlenbeck: the last value (without the mean)
  double decay_ = 0;
  double innovation_ = 0;
};

}  // namespace momentid
