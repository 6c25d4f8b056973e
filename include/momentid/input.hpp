#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "momentid/random.hpp"
#include "momentid/types.hpp"

namespace momentid {

// A stationary input process. Written `KIND:key=value,...`:
//
//   ma:K=10,w=0.1          moving average x_n = sum_{i<K} w_i v_{n-i} of white noise v, the
//                          report's input; K equal weights w, or `weights=[0.3,0.4,0.3]`
//   ma:T=0.1               the same over a window of T seconds: K = T/dt rounded (at least
//                          1), equal weights w (default 1/K, a gain of 1 at 0 Hz); the gain
//                          falls by 3 dB near 0.443/T Hz and to 0 at 1/T Hz
//   ou:tau=0.5             first-order filtered noise with correlation time tau (seconds):
//                          x_{n+1} = a x_n + sqrt(1 - a^2) e_n, a = exp(-dt/tau)
//   white                  a new independent value every step
//   multisine:f1=0.5,f2=5,lines=10,rms=1
//                          a random-phase odd multisine, band-limited to [f1, f2] Hz (below)
//
// `ma`, `ou` and `white` are Gaussian, sampled once per integration step and held constant over
// the step (zero-order hold). `sigma=` and `mean=` set the standard deviation and mean: for `ma`
// those of the white noise v that is averaged (as in the report's program), for `ou` and `white`
// those of x itself. Defaults: sigma=1, mean=0. The default process is `ma:K=10,w=0.1`.
//
// The multisine is a smooth function of time, evaluated exactly wherever the integrator needs it
// (no hold):
//
//   x(t) = mean + A * sum_{j=0}^{L-1} cos(2 pi n_j f0 t + phi_j),   n_j = 2m + 2j + 1,
//   f0 = f2 / (2m + 2L - 1),   A = rms * sqrt(2 / L),
//
// with L = `lines` and m >= 0 the smallest whole number for which the lowest line
// (2m + 1) f0 is at least f1. So the L lines are consecutive odd harmonics of f0, spaced 2 f0
// apart, the highest exactly at f2 and the lowest in [f1, f2]; x is periodic with period 1/f0
// and, over whole periods, its standard deviation is exactly `rms` (equal amplitudes; no line
// at an even harmonic, so a second-order nonlinearity puts no energy on the excited lines). The
// phases phi_j are independent and uniform on [0, 2 pi), drawn from the seed. Required: f1, f2
// and lines, with 0 < f1 < f2 and 1 <= lines <= kMaxLines; optional rms (default 1, > 0) and
// mean (default 0). f2 must also be below the Nyquist frequency 1/(2 dt), which
// SimulationOptions::validate checks.
struct InputSpec {
  using Kind = InputKind;
  Kind kind = Kind::kMovingAverage;
  std::vector<double> weights = std::vector<double>(10, 0.1);
  // ma:T=: the averaging window in seconds, 0 when `weights` are given; `weights` then holds the
  // one weight w when given, else nothing (1/K).
  double window = 0;
  double tau = 1;
  double sigma = 1;
  double mean = 0;
  // Multisine only.
  double f1 = 0, f2 = 0;
  std::uint32_t lines = 0;
  double rms = 1;

  static constexpr std::uint32_t kMaxLines = 10000;
  static constexpr long kMaxWeights = 1000000;

  // Parses the text form above; throws UsageError naming `option` and what is wrong.
  static InputSpec parse(const std::string& text, const std::string& option);
  // The canonical text form, e.g. `ma:K=10,w=0.1,sigma=1,mean=0` or
  // `multisine:f1=0.5,f2=5,lines=10,rms=1,mean=0`.
  std::string text() const;
  // Throws UsageError naming `option` when the spec cannot be simulated at step `dt`: a value
  // parse() would refuse, a multisine whose f2 is not below the Nyquist frequency 1/(2 dt), or
  // a window shorter than half a step or longer than kMaxWeights steps.
  void validate(const std::string& option, double dt) const;
  // The moving average's weights at step `dt` (those of the window, or `weights`).
  std::vector<double> weights_at(double dt) const;
  // Whether the process is held over each step (ma, ou, white) rather than evaluated at every
  // time the integrator asks for (multisine).
  bool held() const { return kind != Kind::kMultisine; }

  // Multisine only: the base frequency f0 and the odd harmonic numbers n_j of the lines, lowest
  // first (the line frequencies are n_j * f0); 0 and none when the band is not valid.
  double base_frequency() const;
  std::vector<std::uint64_t> harmonics() const;
};

// Generates one input's values. A held process gives one value per step; a multisine is a
// function of a clock that counts half steps, so that the integrator can take its value at the
// start, the middle and the end of each step.
//
// Example:
//   InputProcess input(InputSpec::parse("multisine:f1=1,f2=4,lines=4", "--input"), 0.01, 1, 0);
//   double x0 = input.next();            // x(0)
//   double xm = input.middle(), xe = input.end();  // x(dt/2), x(dt)
//   double x1 = input.next();            // x(dt), equal to xe
class InputProcess {
 public:
  InputProcess(const InputSpec& spec, double dt, std::uint64_t seed, std::uint64_t stream);
  // The value for the next step: the value held over it, or the multisine at its start.
  double next();
  // Multisine only: its value at the middle and at the end of the step that next() began.
  double middle() const { return middle_; }
  double end() const { return end_; }
  // Starts a record whose first written row comes after `burn_in` steps. A multisine sets its
  // clock so that row n holds x(n dt) and, for every record after the first, draws new phases,
  // so that separate records are independent. Held processes carry on unchanged.
  void start_record(std::size_t burn_in);

 private:
  // The multisine at `half_steps` * dt / 2.
  double multisine_at(std::int64_t half_steps) const;
  void draw_phases();

  InputSpec spec_;
  PortableRandom random_;
  std::vector<double> history_;  // moving average: the last K noise values, newest at `head_`
  std::size_t head_ = 0;
  double state_ = 0;  // Ornstein-Uhlenbeck: the last value (without the mean)
  double decay_ = 0;
  double innovation_ = 0;
  // Multisine: cycles of each line per half step, the phases in cycles, the amplitude, the clock
  // (in half steps) of the next step's start and the values in the step last begun.
  std::vector<double> cycles_per_half_step_;
  std::vector<double> phases_;
  double amplitude_ = 0;
  std::int64_t clock_ = 0;
  std::int64_t end_clock_ = -1;  // the clock at which end_ was taken (none yet: -1 is odd)
  bool records_started_ = false;
  double middle_ = 0, end_ = 0;
};

}  // namespace momentid
