#pragma once

#include <ginac/ginac.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "momentid/input.hpp"
#include "momentid/metadata.hpp"
#include "momentid/model.hpp"
#include "momentid/parameters.hpp"
#include "momentid/writer.hpp"

namespace momentid {

// A model's equations solved for the state derivatives, y' = f(y, u), with the parameter values
// substituted and compiled to flat arrays of polynomial terms: no symbolic work per evaluation.
// When the coefficients of the derivatives are constants (the usual case, also `a*y2' = ...`),
// the equations are solved once, exactly; otherwise a small linear system is solved at every
// evaluation.
//
// Example:
//   CompiledModel f(model, {GiNaC::numeric(1, 2), 4, 1});
//   f.derivative(y, u, dydt);
class CompiledModel {
 public:
  // `parameters` holds one value per model parameter, in declaration order. Throws ModelError
  // when the model has not one equation per state, or when the equations cannot be solved for the
  // derivatives with these values. Takes the AlgebraLock; the compiled model holds no GiNaC
  // object (the caller's `parameters` are its own to guard).
  CompiledModel(const Model& model, const std::vector<GiNaC::numeric>& parameters);

  int states() const { return states_; }
  int inputs() const { return channels_ - states_; }

  // The model's functions abs(p) and sign(p) (Model::functions), p a polynomial in the states and
  // inputs. Each is evaluated as written unless a mode is set for it, as the switching
  // integrator (simulate/switching.hpp) does to keep the right-hand side smooth within a step:
  // sign(p) then takes the mode's value (+-1 on either side of p = 0, or the value in [-1, 1]
  // that holds a sliding motion on p = 0), abs(p) is mode * p.
  std::size_t functions() const { return functions_.size(); }
  bool is_sign(std::size_t k) const { return functions_[k].sign; }
  // Whether function k's argument holds an input (its switches then come with the input).
  bool reads_inputs(std::size_t k) const {
    return std::any_of(functions_[k].terms.begin(), functions_[k].terms.end(), [&](const auto& t) {
      return std::any_of(t.second.begin(), t.second.end(),
                         [&](const auto& f) { return f.first >= states_; });
    });
  }
  // p of function k at the states y and inputs u.
  double argument(std::size_t k, const double* y, const double* u) const;
  // dp/dt of function k at y, u when the states move at `dydt` (the inputs' own change left
  // out: a sliding motion is a property of the states).
  double argument_rate(std::size_t k, const double* y, const double* u, const double* dydt) const;
  // NaN: evaluated as written. The modes and the sliding set are state of this object, which
  // derivative() reads: one CompiledModel serves one integration at a time (not thread-safe).
  void set_mode(std::size_t k, double mode) const { functions_[k].mode = mode; }
  // Moves y onto p = 0 when function k's argument is one state times a number plus a constant
  // (sign(v), sign(v - 1/2)), which a sliding motion holds there against rounding.
  void project(std::size_t k, double* y, const double* u) const;
  double mode(std::size_t k) const { return functions_[k].mode; }
  // The sign functions whose arguments a sliding motion holds at 0 (Filippov's convention): at
  // every evaluation each takes the value, set as its mode, that keeps the rates of their
  // arguments at 0 (the equations being affine in them).
  void set_sliding(std::vector<std::size_t> functions) const { sliding_ = std::move(functions); }
  const std::vector<std::size_t>& sliding() const { return sliding_; }
  // dydt = f(y, u). Returns false if the derivatives cannot be solved for at this point (a
  // state-dependent coefficient matrix that is singular there).
  [[gnu::always_inline]] bool derivative(const double* y, const double* u, double* dydt) const {
    if (!sliding_.empty()) return slide(y, u, dydt);
    return smooth_derivative(y, u, dydt);
  }

 private:
  [[gnu::always_inline]] bool smooth_derivative(const double* y, const double* u,
                                                double* dydt) const {
    fill_powers(y, u);
    if (!constant_matrix_) return solve(dydt);
    evaluate_all(dydt, static_cast<std::size_t>(states_));
    return true;
  }
  // derivative() with the sliding functions' values solved for.
  bool slide(const double* y, const double* u, double* dydt) const;
  // Sums of coefficient * product of powers of variables, all stored in one flat array: term t
  // of polynomial p is terms_[first_term[p] + t], its factors powers_[factor_index[...]].
  struct TermRef {
    double coefficient;
    std::uint32_t first_factor;
    std::uint32_t factors;
    std::uint32_t polynomial;  // which polynomial the term belongs to
  };
  // Appends a polynomial; returns its index.
  std::size_t compile(const std::map<Monomial, GiNaC::numeric>& terms);
  // out[p] = polynomial p at the powers last filled in, for all `count` polynomials, in one
  // pass over the terms.
  [[gnu::always_inline]] void evaluate_all(double* out, std::size_t count) const {
    const double* powers = powers_.data();
    const std::uint32_t* factors = factor_index_.data();
    const TermRef* terms = terms_.data();
    for (std::size_t p = 0; p < count; ++p) {
      // Summed in a register: adding into out[p] term by term would chain every addition
      // through memory.
      double sum = 0;
      for (std::uint32_t t = first_term_[p]; t < first_term_[p + 1]; ++t) {
        const TermRef& term = terms[t];
        const std::uint32_t* f = factors + term.first_factor;
        double product = term.coefficient;
        switch (term.factors) {
          case 0:
            break;
          case 1:
            product *= powers[f[0]];
            break;
          case 2:
            product *= powers[f[0]] * powers[f[1]];
            break;
          default:
            for (std::uint32_t k = 0; k < term.factors; ++k) product *= powers[f[k]];
        }
        sum += product;
      }
      out[p] = sum;
    }
  }
  [[gnu::always_inline]] void fill_powers(const double* y, const double* u) const {
    for (int v = 0; v < channels_; ++v) fill_power_row(v, v < states_ ? y[v] : u[v - states_]);
    for (std::size_t k = 0; k < functions_.size(); ++k) {
      fill_power_row(variables_ - static_cast<int>(functions_.size()) + static_cast<int>(k),
                     function_value(k, y, u));
    }
  }
  [[gnu::always_inline]] void fill_power_row(int v, double x) const {
    double* row = powers_.data() + power_offset_[static_cast<std::size_t>(v)];
    row[1] = x;
    const int top = max_power_[static_cast<std::size_t>(v)];
    for (int k = 2; k <= top; ++k) row[k] = row[k - 1] * x;
  }
  // Solves M y' = h at the current powers (a state-dependent matrix).
  bool solve(double* dydt) const;
  double function_value(std::size_t k, const double* y, const double* u) const;

  // A function's argument as coefficient * product of (channel, power), and its mode.
  struct Function {
    bool sign = false;
    std::vector<std::pair<double, std::vector<std::pair<int, int>>>> terms;
    int linear_state = -1;  // the state of an argument c y_j + constant, or -1
    double linear_coefficient = 0;
    mutable double mode = std::numeric_limits<double>::quiet_NaN();
  };

  std::vector<TermRef> terms_;
  std::vector<std::uint32_t> first_term_{0};  // per polynomial, plus one end
  std::vector<std::uint32_t> factor_index_;   // into powers_
  std::vector<int> max_power_;                // per variable
  std::vector<std::uint32_t> power_offset_;   // per variable, into powers_
  int states_ = 0;
  int channels_ = 0;  // states and inputs
  int variables_ = 0;
  std::vector<Function> functions_;
  mutable std::vector<std::size_t> sliding_;
  bool constant_matrix_ = true;
  // Constant matrix: polynomial j is the solved f_j. Otherwise polynomials 0..n*n-1 are M
  // (row-major) and n*n..n*n+n-1 are h in M y' = h.
  mutable std::vector<double> powers_;
  mutable std::vector<double> scratch_;
};

// Receives the simulated samples: row n of run r holds t_n = n*dt, the states at t_n and the
// inputs: a held input's value over [t_n, t_{n+1}), a multisine's value at t_n.
class SampleSink {
 public:
  virtual ~SampleSink() = default;
  // `values`: the model's channel_count() values, states then inputs.
  virtual void sample(double t, const double* values, std::size_t run) = 0;
};

// Writes the samples as rows t, channels[, run] (runs numbered from 1), the layout of
// `momentid simulate`: every value (states, then inputs), or the values at `channels`, in that
// order.
class SampleRows : public SampleSink {
 public:
  SampleRows(DataWriter& out, std::size_t values, bool with_run)
      : SampleRows(out, all_channels(values), with_run) {}
  SampleRows(DataWriter& out, std::vector<std::size_t> channels, bool with_run)
      : out_(out),
        channels_(std::move(channels)),
        row_(channels_.size() + 1 + (with_run ? 1 : 0)),
        with_run_(with_run) {}
  void sample(double t, const double* values, std::size_t run) override {
    row_[0] = t;
    for (std::size_t c = 0; c < channels_.size(); ++c) row_[c + 1] = values[channels_[c]];
    if (with_run_) row_.back() = static_cast<double>(run + 1);
    out_.row(row_.data());
  }

 private:
  static std::vector<std::size_t> all_channels(std::size_t values) {
    std::vector<std::size_t> out(values);
    for (std::size_t c = 0; c < values; ++c) out[c] = c;
    return out;
  }

  DataWriter& out_;
  std::vector<std::size_t> channels_;
  std::vector<double> row_;
  bool with_run_;
};

// White Gaussian measurement noise on one written channel (a state or an input, by name), with
// standard deviation `relative` times the standard deviation of the clean channel.
struct ChannelNoise {
  std::string channel;
  double relative = 0;
};

// How to simulate (docs/cli/simulate.md, "momentid simulate").
struct SimulationOptions {
  // By name; a parameter absent takes its nominal value (`param k = 4` in the model file).
  ParameterValues parameters;
  std::vector<InputSpec> inputs;  // one per model input
  double dt = 0.01;
  std::size_t samples = 10000;  // per run
  std::size_t burn_in =
      10000;  // steps discarded before each run (before the first with --continue)
  std::size_t runs = 1;
  bool continue_runs = false;  // start each run from the previous run's last state
  std::uint64_t seed = 1;
  // Measurement noise, added to the samples after they are simulated: the trajectory does not
  // see it. The clean channel's standard deviation is taken over all written samples (all runs,
  // divided by their number), which costs a first, silent run of the same simulation. The noise
  // on channel c (its index among the states, then inputs) comes from random stream
  // kNoiseStream + c, independent of the inputs' streams 0, 1, ... and of the other channels.
  // A relative level of 0 adds nothing.
  std::vector<ChannelNoise> noise;
  // The channels simulate_to_file writes, in this order; empty: the states, then the inputs.
  // A SampleSink always receives every channel.
  std::vector<std::string> observe;

  // Throws UsageError naming the first option that `model` cannot be simulated with: a parameter
  // value for a name the model does not have, a count of input processes that differs from the
  // model's, a dt outside [kMinStep, kMaxStep] or not finite, no samples or no runs, an input
  // process that is not valid at this dt (InputSpec::validate), an unknown or repeated channel in
  // `noise` or `observe`, a noise level that is negative or not finite, noise on a channel not
  // observed; ModelError naming a parameter that has a value neither here nor in the model.
  void validate(const Model& model) const;
  static constexpr double kMinStep = 1e-9;
  static constexpr double kMaxStep = 1e6;
  static constexpr std::uint64_t kNoiseStream = std::uint64_t{1} << 32;
};

// Parses noise levels `CHANNEL=REL` (`y=0.05`), as `--noise` takes them. Throws UsageError for
// an item without `=` or a level that is not a number; SimulationOptions::validate checks the
// channels and the values.
std::vector<ChannelNoise> parse_noise(const std::vector<std::string>& items);

// Integrates the model with the classical fourth-order Runge-Kutta method at a fixed step from
// y = 0: a held input is constant over the step, a multisine is evaluated at each stage's time
// (t, t + dt/2, t + dt). Throws Error when a state becomes non-finite or exceeds kBlowUpBound,
// naming the state, the time, the run and the parameter values. The options are validated
// first. With `options.noise`, the sink receives the samples with measurement noise, after a
// first run that measures the channels' standard deviations (see noise_standard_deviations).
void simulate(const Model& model, const SimulationOptions& options, SampleSink& sink);
// The same with the noise standard deviations already known, one per `options.noise` entry
// (std::invalid_argument otherwise): one run.
void simulate(const Model& model, const SimulationOptions& options, SampleSink& sink,
              const std::vector<double>& noise_sd);
inline constexpr double kBlowUpBound = 1e100;

// Writes the samples into arrays a front end holds, one per channel in `channels` (indices of
// the model's variables, observed_channels()), the time into `time` and the run's number (1,
// 2, ...) into `run` unless it is null, every run's `samples` rows one run after the other.
class ArraySink : public SampleSink {
 public:
  ArraySink(std::vector<double*> columns, std::vector<std::size_t> channels, double* time,
            double* run, std::size_t samples)
      : columns_(std::move(columns)),
        channels_(std::move(channels)),
        time_(time),
        run_(run),
        samples_(samples) {}
  void sample(double t, const double* values, std::size_t run) override {
    if (run != run_index_) {
      run_index_ = run;
      row_in_run_ = 0;
    }
    const std::size_t row = run * samples_ + row_in_run_++;
    time_[row] = t;
    if (run_ != nullptr) run_[row] = static_cast<double>(run + 1);
    for (std::size_t c = 0; c < channels_.size(); ++c) columns_[c][row] = values[channels_[c]];
  }

 private:
  std::vector<double*> columns_;
  std::vector<std::size_t> channels_;
  double *time_, *run_;
  std::size_t samples_, run_index_ = 0, row_in_run_ = 0;
};

// Watches a simulation for a step too coarse for its dynamics, passing every sample on to `next`.
// At up to kPoints samples spread over the record it linearises the model there (a Jacobian by
// central differences) and keeps the largest modulus of its eigenvalues, |lambda|; the
// fourth-order Runge-Kutta step is accurate for |lambda| dt well below 1 and unstable beyond
// about 2.8. A nonlinear model is linearised where its states are, so a hardening spring
// counts at the amplitudes reached.
//
// Example:
//   StepCheck check(model, options, rows);
//   simulate(model, options, check);
//   if (auto w = check.warning()) std::cerr << "warning: " << *w << "\n";
class StepCheck : public SampleSink {
 public:
  StepCheck(const Model& model, const SimulationOptions& options, SampleSink& next);
  void sample(double t, const double* values, std::size_t run) override;
  // The largest |lambda| dt seen, and where.
  double largest() const { return largest_; }
  // A warning naming the eigenvalue, the time and run, and a step that would do, when the
  // largest |lambda| dt exceeds kLimit.
  std::optional<std::string> warning() const;
  static constexpr double kLimit = 0.5;
  static constexpr std::size_t kPoints = 256;

 private:
  CompiledModel f_;
  SampleSink& next_;
  double dt_;
  std::size_t stride_, seen_ = 0;
  double largest_ = 0, largest_t_ = 0;
  std::size_t largest_run_ = 0;
};

// The absolute standard deviation of each `options.noise` entry: its relative level times the
// standard deviation of the clean channel over all written samples. Runs the simulation once,
// without writing, when a level is not 0. The options are validated first.
std::vector<double> noise_standard_deviations(const Model& model, const SimulationOptions& options);

// The metadata `momentid simulate` writes: model, dt, input-hold, seed, samples, runs, burn-in,
// continue and, with `observe`, the observed channels (`observe=y,x`) on one line; the parameter
// values (`param.NAME`) on the next; each input process (`input.NAME`) on a line of its own;
// with noise, a line with each entry's relative level and absolute standard deviation
// (`noise.y=0.05 noise-sd.y=0.0231`), for which `noise_sd` holds one value per entry
// (std::invalid_argument otherwise).
// `input-hold` is `zoh` when every input is held (or there is none), `sample` when every input
// is a multisine, and `mixed` otherwise, when each input's line also carries
// `input-hold.NAME=zoh` or `input-hold.NAME=sample`.
DataMetadata simulation_metadata(const Model& model, const SimulationOptions& options,
                                 const std::vector<double>& noise_sd = {});

// The indices (states, then inputs) of the channels that `options.observe` names, in its order;
// every channel when it is empty. The options must be valid (SimulationOptions::validate).
std::vector<std::size_t> observed_channels(const Model& model, const SimulationOptions& options);

// Simulates into a data file in the layout of `momentid simulate`: columns t, the observed
// channels (by default the states, then the inputs) and, for several runs, `run` (from 1), with
// simulation_metadata(); in `format` (simulation_format() tells it from the name), written whole
// or not at all (see DataWriter). `path` "-" is standard output. With noise, the simulation runs
// twice: once to measure the channels' standard deviations, which the metadata records, and once
// to write. Returns the warnings of a StepCheck and, for a .npy file, DataWriter::note().
std::vector<std::string> simulate_to_file(const Model& model, const SimulationOptions& options,
                                          const std::string& path, DataWriter::Format format);

// Evaluates a sampled signal between its samples at fixed fractions of the sample interval.
//
// Example:
//   Interpolator half(Interpolation::kSinc, {0.5});
//   double x = half(u, n, 0);  // u at t_n + dt/2
class Interpolator {
 public:
  // Fractions in (0, 1).
  Interpolator(Interpolation method, std::vector<double> fractions);
  // The signal `u` (all its samples) at t_n + fractions[k] dt, for n < u.size() - 1.
  double operator()(const std::vector<double>& u, std::size_t n, std::size_t k) const;

 private:
  Interpolation method_;
  std::vector<double> fractions_;
  std::vector<std::vector<double>> sinc_;  // per fraction, the weights of u[n-23] .. u[n+24]
};

// The response of a model to recorded inputs, integrated with the classical Runge-Kutta method
// in `substeps` equal steps per sample interval, one run at a time from a given initial state.
//
// Example:
//   RecordSimulator sim(model, {{"k", 4.1}}, {Interpolation::kSinc}, 0.01, 2);
//   auto states = sim.run({x}, {y0, v0}, 0.0, 1, x.size());  // states[j][n]: state j at row n
class RecordSimulator {
 public:
  // `parameters` by name, the others at their nominal values; one interpolation method per model
  // input; `substeps` from 1 to kMaxSubsteps. Throws UsageError and ModelError as
  // parameter_vector does, and ModelError as CompiledModel does.
  RecordSimulator(const Model& model, const ParameterValues& parameters,
                  std::vector<Interpolation> methods, double dt, int substeps = 1);
  // `inputs[i][n]`: input i at row n, at least `rows` of them; `initial`: one value per state.
  // Returns states[j][n], the state j at row n, for `rows` rows. Throws Error naming the time
  // (`start` + n dt), the run and the state when the simulation blows up or meets a point where
  // the derivatives cannot be solved for, and std::invalid_argument for arrays of the wrong
  // sizes.
  std::vector<std::vector<double>> run(const std::vector<std::vector<double>>& inputs,
                                       const std::vector<double>& initial, double start,
                                       std::size_t run_number, std::size_t rows) const;
  // The columns of the model's measured derivatives (Model::measured_derivatives()) along
  // `states` as run() returns them, from the equations at each row's states and inputs.
  std::vector<std::vector<double>> derivatives(
      const std::vector<std::vector<double>>& states,
      const std::vector<std::vector<double>>& inputs) const;

  static constexpr int kMaxSubsteps = 64;

 private:
  const Model& model_;
  std::string parameter_text_;  // the values, for messages (no GiNaC object kept)
  CompiledModel f_;
  std::vector<Interpolation> methods_;
  double dt_;
  int substeps_;
  std::vector<Interpolator> within_;  // per input, at the substeps' starts, middles and ends
};

// `assignments` (`k=4`, `eps=-0.5`) by name, each kept as the exact decimal it is. Throws
// UsageError naming `option` for an entry without '=', a name that is not a parameter of the
// model, or a value that is not a decimal number.
ParameterValues parse_parameter_values(const Model& model,
                                       const std::vector<std::string>& assignments,
                                       const std::string& option = "parameters");
// The compiled form of `values`: one value per model parameter, in declaration order, the given
// one or else the nominal one (a decimal exact, a double as it is). Throws UsageError naming
// `option` for a name that is not a parameter of the model, and ModelError naming a parameter
// that has no value either way.
std::vector<GiNaC::numeric> parameter_vector(const Model& model, const ParameterValues& values,
                                             const std::string& option = "parameters");

}  // namespace momentid
