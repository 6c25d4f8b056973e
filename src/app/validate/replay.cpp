#include "app/validate/replay.hpp"

#include <ceres/ceres.h>

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

// Whether state j without a column starts from a derivative of its base's column (a cubic through
// the first samples).
bool read_as_derivative(const Record& record, const std::vector<VariableReading>& readings,
                        std::size_t j) {
  const VariableReading& r = readings[j];
  return record.column_of(j) < 0 && r.base >= 0 && r.order >= 0 && r.order <= 3;
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
    } else if (const VariableReading& r = readings[j]; read_as_derivative(record, readings, j)) {
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
    // A hold given with the record (arrays carry no metadata), else the metadata's.
    const InputHold hold = options.record.hold.value_or(record.metadata.input_hold(input.name));
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

// The rows whose simulation error fixes the states read as derivatives at a run's start
// (fit_start): kStartFitSpan times the lag at which the first measured column's autocorrelation
// falls below 1/2 (about a sixth of a period of an oscillation), from kStartFitRows.first to
// .second rows. A cubic through the first kStartSamples samples gives such a state exactly on a
// smooth record, but noise of 2% of y's spread made v 27 where it was -19 at 1024 Hz (an
// oscillator under a multisine), which put the simulation on another of the force's responses.
constexpr std::size_t kStartFitSpan = 8;
constexpr std::pair<std::size_t, std::size_t> kStartFitRows{4 * Replay::kStartSamples, 1024};
constexpr int kStartFitIterations = 20;

std::size_t start_fit_rows(const std::vector<double>& column) {
  const std::size_t n = std::min<std::size_t>(column.size(), 4096);
  double mean = 0;
  for (std::size_t k = 0; k < n; ++k) mean += column[k];
  mean /= static_cast<double>(n);
  const auto covariance = [&](std::size_t lag) {
    double sum = 0;
    for (std::size_t k = lag; k < n; ++k) sum += (column[k] - mean) * (column[k - lag] - mean);
    return sum;
  };
  const double variance = covariance(0);
  std::size_t lag = 1;
  while (lag < n / 2 && covariance(lag) > 0.5 * variance) ++lag;
  return std::clamp(kStartFitSpan * lag, kStartFitRows.first, kStartFitRows.second);
}

// The simulation's error in each measured state over the first `rows` rows of a run, relative to
// the column's spread, as a function of the initial values of the states `unknown` names (the
// others at `initial`): Ceres' residuals (false where the simulation fails).
struct StartError {
  const RecordSimulator* simulator;
  const RecordRun* run;
  const std::vector<std::vector<double>>* inputs;
  std::vector<double> initial;
  std::vector<std::size_t> unknown, states, columns;
  std::vector<double> spread;
  std::size_t rows = 0;
  bool operator()(double const* const* x, double* residuals) const {
    std::vector<double> start = initial;
    for (std::size_t u = 0; u < unknown.size(); ++u) start[unknown[u]] = x[0][u];
    std::vector<std::vector<double>> simulated;
    try {
      simulated = simulator->run(*inputs, start, run_start(*run), 0, rows);
    } catch (const Error&) {
      return false;
    }
    for (std::size_t i = 0; i < states.size(); ++i) {
      for (std::size_t t = 0; t < rows; ++t) {
        residuals[i * rows + t] =
            (simulated[states[i]][t] - run->columns[columns[i]][t]) / spread[i];
      }
    }
    return std::all_of(residuals, residuals + rows * states.size(),
                       [](double e) { return std::isfinite(e); });
  }
};

// The initial values of the states that `free` marks, fitted (Ceres' Levenberg-Marquardt) so that
// the simulation follows the measured states' columns over the first rows of the run
// (start_fit_rows, StartError), `inputs` the run's (run_inputs). Returns the rows fitted, or 0
// when the fit did not lower the error (the start is left as it was).
std::size_t fit_start(const Record& record, const RecordRun& run,
                      const std::vector<std::vector<double>>& inputs,
                      const RecordSimulator& simulator, const std::vector<bool>& free,
                      std::vector<double>& initial) {
  StartError error{&simulator, &run, &inputs, initial, {}, {}, {}, {}, 0};
  for (std::size_t j = 0; j < free.size(); ++j) {
    if (free[j]) error.unknown.push_back(j);
    if (const int c = record.column_of(j); c >= 0) {
      error.states.push_back(j);
      error.columns.push_back(static_cast<std::size_t>(c));
    }
  }
  if (error.states.empty() || error.unknown.empty() || run.rows() < kStartFitRows.first) return 0;
  error.rows = std::min(run.rows(), start_fit_rows(run.columns[error.columns[0]]));
  for (std::size_t c : error.columns) {
    const auto first = run.columns[c].begin();
    const double s = spread_of({first, first + static_cast<std::ptrdiff_t>(error.rows)});
    error.spread.push_back(s > 0 ? s : 1.0);
  }
  std::vector<double> x;
  for (std::size_t j : error.unknown) x.push_back(initial[j]);
  const auto residuals = static_cast<int>(error.rows * error.states.size());
  auto* cost =
      new ceres::DynamicNumericDiffCostFunction<StartError, ceres::CENTRAL>(new StartError(error));
  cost->AddParameterBlock(static_cast<int>(x.size()));
  cost->SetNumResiduals(residuals);
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, x.data());
  ceres::Solver::Options options;
  options.max_num_iterations = kStartFitIterations;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable() || !(summary.final_cost < summary.initial_cost)) return 0;
  for (std::size_t u = 0; u < error.unknown.size(); ++u) initial[error.unknown[u]] = x[u];
  return error.rows;
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
  // The states read as derivatives of a column at each run's start are fitted to its first rows.
  std::vector<bool> derived(model.states().size(), false);
  for (std::size_t j = 0; j < derived.size(); ++j) {
    derived[j] = read_as_derivative(record, readings, j) && readings[j].order >= 1;
  }
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const RecordRun& run = record.runs[r];
    const std::vector<std::vector<double>> inputs = run_inputs(model, record, run);
    const std::size_t fitted = fit_start(record, run, inputs, simulator, derived, out.initial[r]);
    for (std::size_t j = 0; r == 0 && fitted > 0 && j < derived.size(); ++j) {
      if (derived[j]) {
        out.initial_how[j] += ", then fitted by least squares to the first " +
                              std::to_string(fitted) + " rows of the record";
      }
    }
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
