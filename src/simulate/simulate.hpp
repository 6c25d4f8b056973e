#pragma once

#include <ginac/ginac.h>

#include <cstdint>
#include <string>
#include <vector>

#include "model/model.hpp"
#include "simulate/input.hpp"

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
  bool derivative(const double* y, const double* u, double* dydt) const;

 private:
  // Sum of coefficient * product of powers of variables, stored flat.
  struct Polynomial {
    std::vector<double> coefficients;
    std::vector<std::uint32_t> first_factor;  // per term, into the factor arrays; one extra end
    std::vector<std::uint32_t> factor_power_index;  // variable * stride + power
  };
  Polynomial compile(const std::map<Monomial, GiNaC::numeric>& terms);
  double evaluate(const Polynomial& p) const;
  void fill_powers(const double* y, const double* u) const;

  int states_ = 0;
  int variables_ = 0;
  int stride_ = 2;  // highest power + 1
  bool constant_matrix_ = true;
  std::vector<Polynomial> rates_;   // constant matrix: the solved f_j
  std::vector<Polynomial> matrix_;  // otherwise: M (row-major) and h in M y' = h
  std::vector<Polynomial> forcing_;
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

// How to simulate (README, "momentid simulate").
struct SimulationOptions {
  std::vector<GiNaC::numeric> parameters;  // one per model parameter
  std::vector<InputSpec> inputs;           // one per model input
  double dt = 0.01;
  std::size_t samples = 10000;  // per run
  std::size_t burn_in = 10000;  // steps discarded before each run (before the first with --continue)
  std::size_t runs = 1;
  bool continue_runs = false;  // start each run from the previous run's last state
  std::uint64_t seed = 1;
};

// Integrates the model with the classical fourth-order Runge-Kutta method at a fixed step, each
// input held constant over a step, from y = 0. Throws Error when a state becomes non-finite or
// exceeds kBlowUpBound, naming the state, the time, the run and the parameter values.
void simulate(const Model& model, const SimulationOptions& options, SampleSink& sink);
inline constexpr double kBlowUpBound = 1e100;

// The values of the model's parameters: nominal values, overridden by `assignments` (`k=4`,
// `eps=-0.5`, exact decimals). Throws UsageError for an unknown name or a bad number, and
// ModelError naming a parameter that has no value.
std::vector<GiNaC::numeric> parameter_values(const Model& model,
                                             const std::vector<std::string>& assignments);

// The shortest decimal text that reads back as exactly `x`.
std::string shortest_decimal(double x);

}  // namespace momentid
