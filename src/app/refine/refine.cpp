// refine: the simulation error of a model through a record's inputs, minimised over its
// parameters by Ceres Solver from a start (docs/refine.md). The record is read and replayed as
// validate does (validate/record.cpp, validate/replay.cpp); each evaluation of the error compiles
// the model at the trial values and simulates every run.

#include "momentid/refine.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "app/refine/input_band.hpp"
#include "app/validate/fit.hpp"
#include "app/validate/record.hpp"
#include "app/validate/replay.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/error.hpp"
#include "solve/distributions.hpp"

namespace momentid {

void RefineOptions::validate(const Model& model) const {
  for (const std::string& name : free) {
    if (model.parameter_index(name) < 0) {
      throw UsageError("free", "'" + name + "' is not a parameter of model " + model.name());
    }
  }
  if (max_iterations < 1 || max_iterations > kMaxIterations) {
    throw UsageError("max-iterations", "expected a number from 1 to " +
                                           std::to_string(kMaxIterations) + ", found " +
                                           std::to_string(max_iterations));
  }
}

bool RefineResult::moved() const {
  return std::any_of(parameters.begin(), parameters.end(),
                     [](const RefinedParameter& p) { return p.moved; });
}

namespace {

// The record as the error compares it: each run's inputs and initial state, and per compared
// output its weight (one over its rms error at the start).
struct Comparison {
  const Model& model;
  const Record& record;
  std::vector<Interpolation> interpolation;
  int substeps = 1;
  std::vector<std::vector<std::vector<double>>> inputs;  // per run
  std::vector<std::vector<double>> initial;              // per run
  std::vector<std::size_t> outputs, skip;
  std::vector<double> weights;
  ParameterValues base;            // every other parameter's value
  std::vector<std::string> names;  // the refined parameters

  std::size_t residuals() const {
    std::size_t rows = 0;
    for (std::size_t r = 0; r < record.runs.size(); ++r) rows += record.runs[r].rows() - skip[r];
    return rows * outputs.size();
  }

  // The errors measured - simulated at parameter values `p`, weighted, into `out`, output by
  // output within each run; false when the simulation fails there.
  bool errors(const double* p, double* out, bool weighted = true) const {
    ParameterValues values = base;
    for (std::size_t i = 0; i < names.size(); ++i) values.insert_or_assign(names[i], p[i]);
    try {
      const RecordSimulator simulator(model, values, interpolation, record.dt, substeps);
      for (std::size_t r = 0; r < record.runs.size(); ++r) {
        const RecordRun& run = record.runs[r];
        const std::vector<std::vector<double>> states =
            simulator.run(inputs[r], initial[r], run_start(run), run_label(record, r), run.rows());
        std::vector<std::vector<double>> derivatives;
        if (outputs.back() >= model.states().size()) {
          derivatives = simulator.derivatives(states, inputs[r]);
        }
        for (std::size_t o = 0; o < outputs.size(); ++o) {
          const std::size_t j = outputs[o];
          const std::vector<double>& sim =
              j < states.size() ? states[j] : derivatives[j - states.size()];
          const std::vector<double>& y =
              run.columns[static_cast<std::size_t>(record.column_of(output_variable(model, j)))];
          const double w = weighted ? weights[o] : 1.0;
          for (std::size_t n = skip[r]; n < y.size(); ++n) *out++ = w * (y[n] - sim[n]);
        }
      }
    } catch (const Error&) {
      return false;  // blown up, or a point where the derivatives cannot be solved for
    }
    return true;
  }
};

// Ceres' view of the error: one residual block over every refined parameter.
struct SimulationError {
  const Comparison* comparison;
  bool operator()(double const* const* p, double* residuals) const {
    if (!comparison->errors(p[0], residuals)) return false;
    const std::size_t n = comparison->residuals();
    return std::all_of(residuals, residuals + n, [](double e) { return std::isfinite(e); });
  }
};

// The rms of each output's unweighted error at `p`, over the compared rows.
std::vector<double> output_rms(const Comparison& c, const std::vector<double>& p) {
  std::vector<double> e(c.residuals());
  if (!c.errors(p.data(), e.data(), false)) {
    return std::vector<double>(c.outputs.size(), NAN);
  }
  std::vector<double> sum(c.outputs.size(), 0.0);
  std::vector<std::size_t> count(c.outputs.size(), 0);
  std::size_t k = 0;
  for (std::size_t r = 0; r < c.record.runs.size(); ++r) {
    const std::size_t rows = c.record.runs[r].rows() - c.skip[r];
    for (std::size_t o = 0; o < c.outputs.size(); ++o) {
      for (std::size_t n = 0; n < rows; ++n, ++k) sum[o] += e[k] * e[k];
      count[o] += rows;
    }
  }
  for (std::size_t o = 0; o < sum.size(); ++o) sum[o] = std::sqrt(sum[o] / count[o]);
  return sum;
}

// The parameters refined (RefineOptions::free), in declaration order.
std::vector<std::string> refined_names(const Model& model, const RefineOptions& options) {
  std::vector<std::string> out;
  for (const Declaration& p : model.parameters()) {
    bool refined = false;
    if (!options.free.empty()) {
      refined = std::find(options.free.begin(), options.free.end(), p.name) != options.free.end();
    } else if (!options.start.empty()) {
      refined = std::any_of(options.start.begin(), options.start.end(), [&](const auto& s) {
        return s.name == p.name && !s.fixed && s.identifiable;
      });
    } else {
      refined = !p.fixed;
    }
    if (refined) out.push_back(p.name);
  }
  if (out.empty()) {
    throw UsageError("free", "no parameter of model " + model.name() + " is left to refine");
  }
  return out;
}

// The rows each run leaves out (RefineOptions::skip).
std::vector<std::size_t> chosen_skips(const Model& model, const Replay& replay,
                                      const ParameterValues& values, const RefineOptions& options) {
  const Record& record = replay.record;
  const RecordSimulator simulator(model, values, replay.interpolation, record.dt, replay.substeps);
  std::vector<std::size_t> out;
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    std::size_t skip = options.skip.value_or(0);
    if (!options.skip && !model.inputs().empty()) {
      skip = forgetting_row(simulator, run_inputs(model, record, record.runs[r]), replay.initial[r],
                            replay.simulated[r], run_start(record.runs[r]), run_label(record, r))
                 .first;
    }
    const std::size_t rows = record.runs[r].rows();
    if (skip >= rows) {
      throw DataError(file_start(record.name),
                      "run " + std::to_string(run_label(record, r)) + " has " +
                          std::to_string(rows) + " rows: none is left to compare after skipping " +
                          std::to_string(skip));
    }
    out.push_back(skip);
  }
  return out;
}

// The error of `c` over the values `p` as Ceres' problem.
void add_error(ceres::Problem& problem, const Comparison& c, std::vector<double>& p) {
  auto* cost = new ceres::DynamicNumericDiffCostFunction<SimulationError, ceres::CENTRAL>(
      new SimulationError{&c});
  cost->AddParameterBlock(static_cast<int>(p.size()));
  cost->SetNumResiduals(static_cast<int>(c.residuals()));
  problem.AddResidualBlock(cost, nullptr, p.data());
}

// The error of `c` minimised over `p` from its values.
ceres::Solver::Summary minimise(const Comparison& c, std::vector<double>& p, int iterations,
                                double tolerance) {
  ceres::Problem problem;
  add_error(problem, c, p);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = iterations;
  solver.function_tolerance = tolerance;
  solver.parameter_tolerance = tolerance;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  return summary;
}

// The weighted errors of `c` at `p` and their Jacobian, as Ceres computes them (central
// differences); false when the simulation fails there.
bool linearise(const Comparison& c, std::vector<double> p, std::vector<double>& e,
               Eigen::MatrixXd& j) {
  ceres::Problem problem;
  add_error(problem, c, p);
  ceres::CRSMatrix jacobian;
  double cost = 0;
  if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, &e, nullptr, &jacobian)) {
    return false;
  }
  j = Eigen::MatrixXd::Zero(jacobian.num_rows, static_cast<Eigen::Index>(p.size()));
  for (int row = 0; row < jacobian.num_rows; ++row) {
    for (int k = jacobian.rows[static_cast<std::size_t>(row)];
         k < jacobian.rows[static_cast<std::size_t>(row) + 1]; ++k) {
      j(row, jacobian.cols[static_cast<std::size_t>(k)]) =
          jacobian.values[static_cast<std::size_t>(k)];
    }
  }
  return true;
}

// The sandwich covariance of the refined values: (J'J)^-1 S (J'J)^-1, S the long-run covariance
// of J'e from the sums over RefineOptions::kBatches batches of consecutive rows of each run.
// Returns it empty when J'J is singular.
Eigen::MatrixXd sandwich(const Comparison& c, const Eigen::MatrixXd& j,
                         const std::vector<double>& e) {
  const Eigen::Index p = j.cols();
  const Eigen::MatrixXd jtj = j.transpose() * j;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(jtj);
  if (!lu.isInvertible()) return {};
  // Batches of time: the same rows of every output go to the same batch.
  std::size_t total = 0;
  for (std::size_t r = 0; r < c.record.runs.size(); ++r)
    total += c.record.runs[r].rows() - c.skip[r];
  const std::size_t batches = std::min(RefineOptions::kBatches, total);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(batches), p);
  std::size_t k = 0, time = 0;
  for (std::size_t r = 0; r < c.record.runs.size(); ++r) {
    const std::size_t rows = c.record.runs[r].rows() - c.skip[r];
    for (std::size_t o = 0; o < c.outputs.size(); ++o) {
      for (std::size_t n = 0; n < rows; ++n, ++k) {
        const auto b = static_cast<Eigen::Index>((time + n) * batches / total);
        g.row(b) += e[k] * j.row(static_cast<Eigen::Index>(k));
      }
    }
    time += rows;
  }
  const Eigen::RowVectorXd mean = g.colwise().mean();
  const Eigen::MatrixXd centred = g.rowwise() - mean;
  const double b = static_cast<double>(batches);
  const Eigen::MatrixXd s = centred.transpose() * centred * (b / (b - 1));
  const Eigen::MatrixXd inverse = lu.inverse();
  return inverse * s * inverse;
}

// The bias that the inputs' white noise gives the refined values `p` (errors in variables), by
// simulation and extrapolation: the refinement again, from `p`, with noise of the same variance
// added to each noisy input (before its low-pass), in RefineOptions::kNoiseReplicates replicates
// of fixed seeds; the bias grows with the noise's variance, so the shift from doubling it is the
// bias at the record's noise. (One Gauss-Newton step from `p` measures a tenth of the shift on
// a lightly damped chain: the refinement must be run to its end.) Returns the shift per parameter
// (empty: no input is noisy) and, in `spread`, the covariance of the replicates' mean shift.
std::vector<double> noise_shift(const Comparison& c,
                                const std::vector<std::vector<std::vector<double>>>& raw,
                                const std::vector<InputBand>& bands, const std::vector<double>& p,
                                int iterations, Eigen::MatrixXd& spread) {
  if (std::none_of(bands.begin(), bands.end(), [](const InputBand& b) { return b.noise_rms > 0; }))
    return {};
  const std::size_t k = RefineOptions::kNoiseReplicates;
  Eigen::MatrixXd shifts(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(p.size()));
  for (std::size_t replicate = 0; replicate < k; ++replicate) {
    Comparison noisy = c;
    std::mt19937_64 generator(RefineOptions::kNoiseSeed + replicate);
    std::normal_distribution<double> normal;
    for (std::size_t r = 0; r < raw.size(); ++r) {
      for (const InputBand& band : bands) {
        if (!(band.noise_rms > 0)) continue;
        std::vector<double> x = raw[r][band.index];
        for (double& value : x) value += band.noise_rms * normal(generator);
        if (band.filtered) low_pass(x, c.record.dt, band);
        noisy.inputs[r][band.index] = std::move(x);
      }
    }
    std::vector<double> q = p;
    minimise(noisy, q, iterations, RefineOptions::kReplicateTolerance);
    for (std::size_t j = 0; j < p.size(); ++j) {
      shifts(static_cast<Eigen::Index>(replicate), static_cast<Eigen::Index>(j)) = q[j] - p[j];
    }
  }
  const Eigen::RowVectorXd mean = shifts.colwise().mean();
  const Eigen::MatrixXd centred = shifts.rowwise() - mean;
  spread = centred.transpose() * centred / (static_cast<double>(k) * static_cast<double>(k - 1));
  return {mean.data(), mean.data() + mean.size()};
}

}  // namespace

RefineResult refine(const Model& model, const DataSource& source, const RefineOptions& options) {
  const AlgebraLock lock;
  options.validate(model);
  options.replay.record.validate(&model);
  RefineResult result;
  result.model = std::make_shared<const Model>(model);
  result.data_name = source.name();
  ReplayOptions replay_options = options.replay;
  for (const ParameterEstimate& s : options.start) {
    if (model.parameter_index(s.name) < 0) {
      throw UsageError("start", "'" + s.name + "' is not a parameter of model " + model.name());
    }
    replay_options.parameters.insert_or_assign(s.name, s.estimate);
  }
  const std::vector<std::string> names = refined_names(model, options);
  Record record = read_record(model, source, replay_options);
  center_record(model, record, options.center);
  const Replay replay = replay_record(*result.model, std::move(record), replay_options);

  Comparison c{model, replay.record};
  c.interpolation = replay.interpolation;
  c.substeps = replay.substeps;
  c.initial = replay.initial;
  for (const RecordRun& run : replay.record.runs) {
    c.inputs.push_back(run_inputs(model, replay.record, run));
  }
  const std::vector<std::vector<std::vector<double>>> raw_inputs = c.inputs;
  // A held input is taken as exact: its steps hide white noise from the estimate of it.
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    if (c.interpolation[i] == Interpolation::kHold) continue;
    std::vector<std::vector<double>> runs;
    for (const auto& inputs : c.inputs) runs.push_back(inputs[i]);
    InputBand band = input_band(model.inputs()[i].name, runs, replay.record.dt);
    band.index = i;
    if (band.filtered) {
      for (auto& inputs : c.inputs) low_pass(inputs[i], replay.record.dt, band);
    }
    result.inputs.push_back(band);
  }
  c.outputs = measured_outputs(model, replay.record);
  c.skip = chosen_skips(model, replay, replay_options.parameters, options);
  c.base = replay_options.parameters;
  c.names = names;
  c.weights.assign(c.outputs.size(), 1.0);
  result.skip = c.skip;
  result.substeps = c.substeps;
  result.samples = c.residuals();

  std::vector<double> p;
  for (const std::string& name : names) {
    const auto given = replay_options.parameters.find(name);
    const auto& declared =
        model.parameters()[static_cast<std::size_t>(model.parameter_index(name))];
    if (given != replay_options.parameters.end()) {
      p.push_back(given->second.value);
    } else if (declared.value) {
      p.push_back(declared.value->to_double());
    } else {
      throw ModelError(declared.where, "parameter " + name +
                                           " has no value to start the refinement from: give "
                                           "one (--set " +
                                           name + "=...) or a nominal value");
    }
  }
  const std::vector<double> start = p;
  const std::vector<double> rms_start = output_rms(c, start);
  for (std::size_t o = 0; o < c.outputs.size(); ++o) {
    if (!std::isfinite(rms_start[o])) {
      throw Error("the simulation at the start values fails: validate with them says where");
    }
    c.weights[o] = rms_start[o] > 0 ? 1 / rms_start[o] : 1.0;
  }

  const ceres::Solver::Summary summary =
      minimise(c, p, options.max_iterations, RefineOptions::kTolerance);
  result.cost_start = summary.initial_cost;
  result.cost = summary.final_cost;
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.solver = summary.message;
  Eigen::MatrixXd shift_spread;
  const std::vector<double> shift =
      noise_shift(c, raw_inputs, result.inputs, p, options.max_iterations, shift_spread);
  result.noise_replicates = shift.empty() ? 0 : RefineOptions::kNoiseReplicates;

  const std::vector<double> rms = output_rms(c, p);
  for (std::size_t o = 0; o < c.outputs.size(); ++o) {
    result.outputs.push_back(
        {model.variables()[output_variable(model, c.outputs[o])].name, rms_start[o], rms[o]});
  }
  std::vector<double> e;
  Eigen::MatrixXd j;
  if (!linearise(c, p, e, j)) throw Error("the simulation fails at the refined values");
  Eigen::MatrixXd covariance = sandwich(c, j, e);
  if (shift_spread.size() > 0 && covariance.size() > 0) covariance += shift_spread;
  const std::size_t batches = std::min(RefineOptions::kBatches, result.samples / c.outputs.size());
  result.dof = static_cast<double>(batches) - 1;
  const double t = student_t_quantile(0.975, std::max(1.0, result.dof));
  for (std::size_t i = 0; i < names.size(); ++i) {
    RefinedParameter out;
    out.name = names[i];
    out.start = start[i];
    out.start_error = out.start_low = out.start_high = NAN;
    for (const ParameterEstimate& s : options.start) {
      if (s.name == names[i]) {
        out.start_error = s.std_error;
        out.start_low = s.ci_low;
        out.start_high = s.ci_high;
      }
    }
    out.noise_shift = shift.empty() ? 0.0 : shift[i];
    ParameterEstimate& r = out.refined;
    r.name = names[i];
    r.estimate = p[i] - out.noise_shift;
    const auto d = static_cast<Eigen::Index>(i);
    r.identifiable = covariance.size() > 0 && covariance(d, d) > 0;
    r.std_error = r.identifiable ? std::sqrt(covariance(d, d)) : NAN;
    r.ci_low = r.estimate - t * r.std_error;
    r.ci_high = r.estimate + t * r.std_error;
    out.moved =
        std::isfinite(out.start_low) && (r.estimate < out.start_low || r.estimate > out.start_high);
    result.parameters.push_back(std::move(out));
  }
  result.covariance.assign(names.size(), std::vector<double>(names.size(), NAN));
  for (std::size_t i = 0; i < names.size() && covariance.size() > 0; ++i) {
    for (std::size_t k = 0; k < names.size(); ++k) {
      result.covariance[i][k] =
          covariance(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k));
    }
  }
  if (!result.converged) {
    result.warnings.push_back("the refinement did not converge (" + result.solver +
                              "): its values are where the search stopped");
  }
  if (covariance.size() == 0) {
    result.warnings.push_back(
        "the simulation error does not determine every refined parameter (its Jacobian is "
        "singular): fix some of them (--free names the others)");
  }
  for (const RefinedParameter& q : result.parameters) {
    if (q.moved) {
      result.warnings.push_back(
          q.name +
          " moved beyond the start's 95% interval: the model, or the start's estimate, "
          "is wrong for these data");
    }
  }
  return result;
}

}  // namespace momentid
