#pragma once

#include <ginac/ginac.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "momentid/input.hpp"
#include "momentid/metadata.hpp"
#include "momentid/model.hpp"
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
  // derivatives with these values.
  CompiledModel(const Model& model, const std::vector<GiNaC::numeric>& parameters);

  int states() const { return states_; }
  int inputs() const { return variables_ - states_; }
  // dydt = f(y, u). Returns false if the derivatives cannot be solved for at this point (a
  // state-dependent coefficient matrix that is singular there).
  [[gnu::always_inline]] bool derivative(const double* y, const double* u, double* dydt) const {
    fill_powers(y, u);
    if (!constant_matrix_) return solve(dydt);
    evaluate_all(dydt, static_cast<std::size_t>(states_));
    return true;
  }

 private:
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
    double* powers = powers_.data();
    for (int v = 0; v < variables_; ++v) {
      double* row = powers + power_offset_[static_cast<std::size_t>(v)];
      const double x = v < states_ ? y[v] : u[v - states_];
      row[1] = x;
      const int top = max_power_[static_cast<std::size_t>(v)];
      for (int k = 2; k <= top; ++k) row[k] = row[k - 1] * x;
    }
  }
  // Solves M y' = h at the current powers (a state-dependent matrix).
  bool solve(double* dydt) const;

  std::vector<TermRef> terms_;
  std::vector<std::uint32_t> first_term_{0};  // per polynomial, plus one end
  std::vector<std::uint32_t> factor_index_;   // into powers_
  std::vector<int> max_power_;                // per variable
  std::vector<std::uint32_t> power_offset_;   // per variable, into powers_
  int states_ = 0;
  int variables_ = 0;
  bool constant_matrix_ = true;
  // Constant matrix: polynomial j is the solved f_j. Otherwise polynomials 0..n*n-1 are M
  // (row-major) and n*n..n*n+n-1 are h in M y' = h.
  mutable std::vector<double> powers_;
  mutable std::vector<double> scratch_;
};

// Receives the simulated samples: row n of run r holds t_n = n*dt, the states at t_n and the
// inputs held over [t_n, t_{n+1}).
class SampleSink {
 public:
  virtual ~SampleSink() = default;
  // `values`: states, then inputs.
  virtual void sample(double t, const double* values, std::size_t run) = 0;
};

// Writes the samples as rows t, states, inputs[, run] (runs numbered from 1), the layout of
// `momentid simulate`.
class SampleRows : public SampleSink {
 public:
  SampleRows(DataWriter& out, std::size_t values, bool with_run)
      : out_(out), row_(values + 1 + (with_run ? 1 : 0)), with_run_(with_run) {}
  void sample(double t, const double* values, std::size_t run) override {
    row_[0] = t;
    std::copy(values, values + (row_.size() - 1 - (with_run_ ? 1 : 0)), row_.begin() + 1);
    if (with_run_) row_.back() = static_cast<double>(run + 1);
    out_.row(row_.data());
  }

 private:
  DataWriter& out_;
  std::vector<double> row_;
  bool with_run_;
};

// How to simulate (README, "momentid simulate").
struct SimulationOptions {
  std::vector<GiNaC::numeric> parameters;  // one per model parameter
  std::vector<InputSpec> inputs;           // one per model input
  double dt = 0.01;
  std::size_t samples = 10000;  // per run
  std::size_t burn_in =
      10000;  // steps discarded before each run (before the first with --continue)
  std::size_t runs = 1;
  bool continue_runs = false;  // start each run from the previous run's last state
  std::uint64_t seed = 1;

  // Throws UsageError naming the first option that `model` cannot be simulated with: a count of
  // parameter values or input processes that differs from the model's, a dt outside
  // [kMinStep, kMaxStep] or not finite, no samples or no runs.
  void validate(const Model& model) const;
  static constexpr double kMinStep = 1e-9;
  static constexpr double kMaxStep = 1e6;
};

// Integrates the model with the classical fourth-order Runge-Kutta method at a fixed step, each
// input held constant over a step, from y = 0. Throws Error when a state becomes non-finite or
// exceeds kBlowUpBound, naming the state, the time, the run and the parameter values.
// The options are validated first.
void simulate(const Model& model, const SimulationOptions& options, SampleSink& sink);
inline constexpr double kBlowUpBound = 1e100;

// The metadata `momentid simulate` writes: model, dt, input-hold=zoh, seed, samples, runs,
// burn-in and continue on one line; the parameter values (`param.NAME`) on the next; each input
// process (`input.NAME`) on a line of its own.
DataMetadata simulation_metadata(const Model& model, const SimulationOptions& options);

// Simulates into a data file in the layout of `momentid simulate`: columns t, the states, the
// inputs and, for several runs, `run` (from 1), after simulation_metadata(); written whole or not
// at all (see DataWriter). `path` "-" is standard output.
void simulate_to_file(const Model& model, const SimulationOptions& options, const std::string& path,
                      DataWriter::Format format);

// The values of the model's parameters: nominal values, overridden by `assignments` (`k=4`,
// `eps=-0.5`, exact decimals). Throws UsageError for an unknown name or a bad number, and
// ModelError naming a parameter that has no value.
std::vector<GiNaC::numeric> parameter_values(const Model& model,
                                             const std::vector<std::string>& assignments);

}  // namespace momentid
