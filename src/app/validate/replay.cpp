#include "app/validate/replay.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>
#include <tuple>

#include "app/validate/record.hpp"
#include "app/variables.hpp"
#include "common/decimal.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/lagged.hpp"
#include "momentid/validate.hpp"

namespace momentid {
namespace {

// `scale` times the `order`-th derivative per sample at the first of `count` samples of `base`,
// from a polynomial of degree 3 (fewer with fewer samples) fitted to them; none when the degree
// is below the order.
std::optional<double> start_derivative(const std::vector<double>& base, std::size_t count,
                                       int order, double scale) {
  const int degree = std::min<int>(3, static_cast<int>(count) - 1);
  if (order > degree) return std::nullopt;
  Eigen::MatrixXd a(count, degree + 1);
  Eigen::VectorXd b(count);
  for (std::size_t k = 0; k < count; ++k) {
    for (int p = 0; p <= degree; ++p) a(k, p) = std::pow(static_cast<double>(k), p);
    b(k) = base[k];
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  double factorial = 1;
  for (int p = 2; p <= order; ++p) factorial *= p;
  return scale * factorial * c(order);
}

// The standard deviation of a series about its mean.
double spread_of(const std::vector<double>& series) {
  const auto n = static_cast<double>(series.size());
  double mean = 0, squares = 0;
  for (double x : series) mean += x;
  mean /= n;
  for (double x : series) squares += (x - mean) * (x - mean);
  return std::sqrt(squares / n);
}

// The initial value of each state in `run` and how it was found (see Replay).
std::vector<double> initial_state(const Model& model, const Record& record, const RecordRun& run,
                                  const std::vector<VariableReading>& readings,
                                  std::vector<std::string>* how) {
  const std::size_t states = model.states().size();
  std::vector<double> out(states, 0.0);
  for (std::size_t j = 0; j < states; ++j) {
    const int column = record.column_of(j);
    std::string text;
    if (column >= 0) {
      out[j] = run.columns[static_cast<std::size_t>(column)][0];
      text = "its first sample";
    } else if (const VariableReading& r = readings[j];
               r.base >= 0 && r.order >= 0 && r.order <= 3) {
      const std::vector<double>& base =
          run.columns[static_cast<std::size_t>(record.column_of(static_cast<std::size_t>(r.base)))];
      const std::size_t count = std::min(Replay::kStartSamples, base.size());
      if (const auto d = start_derivative(base, count, r.order, r.scale)) {
        out[j] = *d / std::pow(record.dt, r.order);
      }
      std::string derivative = model.variables()[static_cast<std::size_t>(r.base)].name +
                               std::string(static_cast<std::size_t>(r.order), '\'');
      if (r.scale != 1) derivative = shortest_decimal(r.scale) + "*" + derivative;
      text = derivative + " at the start (a cubic fitted to the first " + std::to_string(count) +
             " samples of " + model.variables()[static_cast<std::size_t>(r.base)].name + ")";
    } else {
      text = readings[j].base >= 0
                 ? "0 (the record shows it only through the integral of " +
                       model.variables()[static_cast<std::size_t>(readings[j].base)].name + ")"
                 : "0 (no column, and no kinematic equation defines it from one)";
    }
    if (how != nullptr) how->push_back(text);
  }
  return out;
}

std::vector<Interpolation> interpolation_methods(const Model& model, const Record& record,
                                                 const ReplayOptions& options) {
  std::vector<Interpolation> out;
  for (const Declaration& input : model.inputs()) {
    if (options.interpolation) {
      out.push_back(*options.interpolation);
      continue;
    }
    const InputHold hold = record.metadata.input_hold(input.name);
    out.push_back(hold == InputHold::kZeroOrderHold ? Interpolation::kHold : Interpolation::kSinc);
  }
  return out;
}

// The fewest substeps (1, 2, 4, ...) for which halving the step changes the simulation of the
// first rows of the first run by less than ReplayOptions::kSubstepTolerance of each state's
// spread. Also returns that change, which is above the tolerance when even kMaxSubsteps do not
// reach it.
std::pair<int, double> chosen_substeps(const Model& model, const ParameterValues& parameters,
                                       const Replay& replay) {
  const Record& record = replay.record;
  const RecordRun& run = record.runs.front();
  const std::size_t rows = std::min(run.rows(), ReplayOptions::kSubstepTrialRows);
  const std::vector<std::vector<double>> inputs = run_inputs(model, record, run);
  const auto simulate = [&](int substeps) {
    return RecordSimulator(model, parameters, replay.interpolation, record.dt, substeps)
        .run(inputs, replay.initial.front(), run_start(run), run_label(record, 0), rows);
  };
  // A step too long for the model can blow the simulation up: that is a reason to halve it.
  const auto attempt = [&](int substeps) -> std::optional<std::vector<std::vector<double>>> {
    try {
      return simulate(substeps);
    } catch (const Error&) {
      return std::nullopt;
    }
  };
  std::optional<std::vector<std::vector<double>>> coarse = attempt(1);
  int substeps = 1;
  double worst = INFINITY;
  for (; substeps < RecordSimulator::kMaxSubsteps; substeps *= 2) {
    std::optional<std::vector<std::vector<double>>> fine = attempt(2 * substeps);
    if (coarse && fine) {
      worst = 0;
      for (std::size_t j = 0; j < fine->size(); ++j) {
        const std::vector<double>& a = (*fine)[j];
        const std::vector<double>& b = (*coarse)[j];
        double change = 0;
        for (std::size_t n = 0; n < rows; ++n) change = std::max(change, std::abs(a[n] - b[n]));
        const double spread = spread_of(a);
        if (spread > 0) worst = std::max(worst, change / spread);
      }
      if (worst < ReplayOptions::kSubstepTolerance) break;
    }
    coarse = std::move(fine);
  }
  // Even the shortest step blows up: the error of that simulation is the answer.
  if (!coarse) simulate(substeps);
  return {substeps, worst};
}

}  // namespace

Replay replay(const Model& model, const DataSource& source, const ReplayOptions& options) {
  const AlgebraLock lock;
  options.record.validate(&model);
  return replay_record(model, read_record(model, source, options), options);
}

Replay replay_record(const Model& model, Record read, const ReplayOptions& options) {
  // Unknown names and parameters without a value are refused before any work.
  parameter_vector(model, options.parameters);
  const ParameterValues& parameters = options.parameters;
  Replay out;
  out.record = std::move(read);
  const Record& record = out.record;
  out.interpolation = interpolation_methods(model, record, options);
  std::vector<bool> measured(model.variables().size(), false);
  for (std::size_t v : record.variables) measured[v] = true;
  const std::vector<VariableReading> readings = variable_readings(model, measured);
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    out.initial.push_back(initial_state(model, record, record.runs[r], readings,
                                        r == 0 ? &out.initial_how : nullptr));
  }
  if (options.substeps) {
    if (*options.substeps < 1 || *options.substeps > RecordSimulator::kMaxSubsteps) {
      throw UsageError("substeps", "expected a number from 1 to " +
                                       std::to_string(RecordSimulator::kMaxSubsteps) + ", found " +
                                       std::to_string(*options.substeps));
    }
    out.substeps = *options.substeps;
  } else {
    std::tie(out.substeps, out.substep_change) = chosen_substeps(model, parameters, out);
    out.substeps_chosen = true;
  }
  const RecordSimulator simulator(model, parameters, out.interpolation, record.dt, out.substeps);
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const RecordRun& run = record.runs[r];
    const std::vector<std::vector<double>> inputs = run_inputs(model, record, run);
    out.simulated.push_back(
        simulator.run(inputs, out.initial[r], run_start(run), run_label(record, r), run.rows()));
    out.derivatives.push_back(simulator.derivatives(out.simulated.back(), inputs));
  }
  return out;
}

std::pair<std::size_t, double> forgetting_row(const RecordSimulator& simulator,
                                              const std::vector<std::vector<double>>& inputs,
                                              const std::vector<double>& initial,
                                              const std::vector<std::vector<double>>& simulated,
                                              double start, std::size_t label) {
  const std::size_t n = initial.size();
  const std::size_t rows = simulated.empty() ? 0 : simulated[0].size();
  std::vector<double> spread(n, 1.0), perturbed = initial;
  for (std::size_t j = 0; j < n; ++j) {
    const double sd = spread_of(simulated[j]);
    if (sd > 0 && std::isfinite(sd)) spread[j] = sd;
    perturbed[j] += 0.1 * spread[j];
  }
  const double initial_size = 0.1 * std::sqrt(static_cast<double>(n));
  const std::size_t horizon = std::max<std::size_t>(1, rows / 2);
  for (std::size_t length = std::min<std::size_t>(1024, horizon);; length *= 2) {
    length = std::min(length, horizon);
    std::vector<std::vector<double>> other;
    try {
      other = simulator.run(inputs, perturbed, start, label, length);
    } catch (const Error&) {
      return {horizon, 1.0};  // the perturbed simulation blew up: it never forgot
    }
    std::size_t last = 0;
    double distance = 0;
    for (std::size_t t = 0; t < length; ++t) {
      double sum = 0;
      for (std::size_t j = 0; j < n; ++j) {
        const double d = (other[j][t] - simulated[j][t]) / spread[j];
        sum += d * d;
      }
      distance = std::sqrt(sum) / initial_size;
      if (!(distance <= 0.01)) last = t;
    }
    if (distance < 1e-4 || length == horizon) return {last + 1, distance};
  }
}

}  // namespace momentid
