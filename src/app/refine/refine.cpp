// refine: the simulation error of a model through a record's inputs, minimised over its
// parameters by Ceres Solver from a start (docs/refine.md). The record is read and replayed as
// validate does (validate/record.cpp, validate/replay.cpp); the error is simulated segment by
// segment, each segment's a residual block of Ceres' problem, the model compiled once for each
// trial value of the parameters and shared by the segments.

#include "momentid/refine.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
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

// A stretch of a run simulated from its own initial state, which is refined with the parameters
// (multiple shooting without continuity between the stretches): a trajectory that forgets its
// start slowly, or a lightly damped chain whose simulation error over a whole run has narrow
// valleys in the parameters, is fitted piece by piece, where the error is nearly quadratic.
struct Segment {
  static constexpr std::size_t kInputMargin = 32;
  std::size_t run = 0, first = 0, rows = 0;
  // The inputs over its rows and up to kInputMargin rows beyond, which the interpolation between
  // the last samples reads.
  std::vector<std::vector<double>> inputs;
  std::vector<double> initial;  // the state at its first row
};

// The record as the error compares it: its segments, and per compared output its weight (one
// over its rms error at the start).
struct Comparison {
  const Model& model;
  const Record& record;
  std::vector<Interpolation> interpolation;
  int substeps = 1;
  std::vector<Segment> segments;
  std::vector<std::size_t> outputs;
  std::vector<double> weights;
  ParameterValues base;            // every other parameter's value
  std::vector<std::string> names;  // the refined parameters
  // The simulators of the last parameter values asked for: the segments share them.
  mutable std::vector<std::pair<std::vector<double>, std::shared_ptr<const RecordSimulator>>> cache;

  std::size_t residuals(const Segment& s) const { return s.rows * outputs.size(); }
  std::size_t residuals() const {
    std::size_t n = 0;
    for (const Segment& s : segments) n += residuals(s);
    return n;
  }

  // The simulator at refined values `p` (throws Error where the model cannot be compiled).
  const RecordSimulator& simulator(const double* p) const {
    std::vector<double> key(p, p + names.size());
    for (const auto& [values, simulator] : cache) {
      if (values == key) return *simulator;
    }
    ParameterValues values = base;
    for (std::size_t i = 0; i < names.size(); ++i) values.insert_or_assign(names[i], p[i]);
    if (cache.size() >= kCached) cache.erase(cache.begin());
    cache.emplace_back(std::move(key), std::make_shared<const RecordSimulator>(
                                           model, values, interpolation, record.dt, substeps));
    return *cache.back().second;
  }

  // The errors measured - simulated over segment `s` at values `p` from its initial state `x0`,
  // weighted, into `out`, output by output; false when the simulation fails there.
  bool errors(const Segment& s, const double* p, const double* x0, double* out,
              bool weighted = true) const {
    try {
      const RecordSimulator& f = simulator(p);
      const RecordRun& run = record.runs[s.run];
      const std::vector<double> initial(x0, x0 + model.states().size());
      const std::vector<std::vector<double>> states =
          f.run(s.inputs, initial, run_start(run) + static_cast<double>(s.first) * record.dt,
                run_label(record, s.run), s.rows);
      std::vector<std::vector<double>> derivatives;
      if (outputs.back() >= model.states().size()) derivatives = f.derivatives(states, s.inputs);
      for (std::size_t o = 0; o < outputs.size(); ++o) {
        const std::size_t j = outputs[o];
        const std::vector<double>& sim =
            j < states.size() ? states[j] : derivatives[j - states.size()];
        const std::vector<double>& y =
            run.columns[static_cast<std::size_t>(record.column_of(output_variable(model, j)))];
        const double w = weighted ? weights[o] : 1.0;
        for (std::size_t n = 0; n < s.rows; ++n) *out++ = w * (y[s.first + n] - sim[n]);
      }
    } catch (const Error&) {
      return false;  // blown up, or a point where the derivatives cannot be solved for
    }
    return true;
  }

  static constexpr std::size_t kCached = 64;
};

// Ceres' view of the error over one segment: the refined parameters, then its initial state.
struct SimulationError {
  const Comparison* comparison;
  const Segment* segment;
  bool operator()(double const* const* p, double* residuals) const {
    if (!comparison->errors(*segment, p[0], p[1], residuals)) return false;
    const std::size_t n = comparison->residuals(*segment);
    return std::all_of(residuals, residuals + n, [](double e) { return std::isfinite(e); });
  }
};

// The values a search moves: the refined parameters and each segment's initial state.
struct Unknowns {
  std::vector<double> p;
  std::vector<std::vector<double>> initial;  // per segment
};

// The rms of each output's unweighted error at `u`, over every segment.
std::vector<double> output_rms(const Comparison& c, const Unknowns& u) {
  std::vector<double> sum(c.outputs.size(), 0.0);
  std::size_t count = 0;
  for (std::size_t b = 0; b < c.segments.size(); ++b) {
    const Segment& s = c.segments[b];
    std::vector<double> e(c.residuals(s));
    if (!c.errors(s, u.p.data(), u.initial[b].data(), e.data(), false)) {
      return std::vector<double>(c.outputs.size(), NAN);
    }
    for (std::size_t o = 0; o < c.outputs.size(); ++o) {
      for (std::size_t n = 0; n < s.rows; ++n) sum[o] += e[o * s.rows + n] * e[o * s.rows + n];
    }
    count += s.rows;
  }
  for (double& s : sum) s = std::sqrt(s / static_cast<double>(count));
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

// The segments of every run after its skip: stretches of the same length (the last of a run takes
// the remainder), RefineOptions::kSegmentRows rows or fewer to make kMinSegments of them, each
// starting from the state the simulation at the start values reached there.
std::vector<Segment> segments_of(const Model& model, const Replay& replay,
                                 const std::vector<std::vector<std::vector<double>>>& inputs,
                                 const std::vector<std::size_t>& skip) {
  std::vector<Segment> out;
  const Record& record = replay.record;
  std::size_t total = 0;
  for (std::size_t r = 0; r < record.runs.size(); ++r) total += record.runs[r].rows() - skip[r];
  const std::size_t length =
      std::clamp(total / RefineOptions::kMinSegments, RefineOptions::kMinSegmentRows,
                 RefineOptions::kSegmentRows);
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const std::size_t rows = record.runs[r].rows();
    const std::size_t count = std::max<std::size_t>(1, (rows - skip[r]) / length);
    for (std::size_t k = 0; k < count; ++k) {
      Segment s;
      s.run = r;
      s.first = skip[r] + k * length;
      s.rows = k + 1 < count ? length : rows - s.first;
      const std::size_t end = std::min(rows, s.first + s.rows + Segment::kInputMargin);
      for (const std::vector<double>& input : inputs[r]) {
        s.inputs.emplace_back(input.begin() + static_cast<long>(s.first),
                              input.begin() + static_cast<long>(end));
      }
      for (std::size_t j = 0; j < model.states().size(); ++j) {
        s.initial.push_back(replay.simulated[r][j][s.first]);
      }
      out.push_back(std::move(s));
    }
  }
  return out;
}

// Ceres' problem of the error of `c` over `u`, one residual block per segment.
void add_error(ceres::Problem& problem, const Comparison& c, Unknowns& u) {
  for (std::size_t b = 0; b < c.segments.size(); ++b) {
    auto* cost = new ceres::DynamicNumericDiffCostFunction<SimulationError, ceres::CENTRAL>(
        new SimulationError{&c, &c.segments[b]});
    cost->AddParameterBlock(static_cast<int>(u.p.size()));
    cost->AddParameterBlock(static_cast<int>(u.initial[b].size()));
    cost->SetNumResiduals(static_cast<int>(c.residuals(c.segments[b])));
    problem.AddResidualBlock(cost, nullptr, u.p.data(), u.initial[b].data());
  }
}

// The error of `c` minimised over `u` from its values, the initial states eliminated in each
// step (Ceres' Schur complement).
ceres::Solver::Summary minimise(const Comparison& c, Unknowns& u, int iterations,
                                double tolerance) {
  ceres::Problem problem;
  add_error(problem, c, u);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = iterations;
  solver.function_tolerance = tolerance;
  solver.parameter_tolerance = tolerance;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  return summary;
}

// The sandwich covariance of the refined parameters at `u`, the initial states profiled out:
// H^-1 S H^-1 with H = sum over segments of A - B D^-1 B' (A = Jp'Jp, B = Jp'Jx, D = Jx'Jx of the
// segment's weighted errors' Jacobian in the parameters p and its initial state x) and S the
// covariance of the segments' scores Jp'e, each segment a batch (at the minimum Jx'e = 0). Empty
// when H is singular, or the simulation fails at `u`.
Eigen::MatrixXd sandwich(const Comparison& c, Unknowns& u) {
  ceres::Problem problem;
  add_error(problem, c, u);
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks.push_back(u.p.data());
  for (auto& x : u.initial) evaluate.parameter_blocks.push_back(x.data());
  problem.GetResidualBlocks(&evaluate.residual_blocks);
  ceres::CRSMatrix jacobian;
  std::vector<double> e;
  double cost = 0;
  if (!problem.Evaluate(evaluate, &cost, &e, nullptr, &jacobian)) return {};
  const auto np = static_cast<Eigen::Index>(u.p.size());
  const auto ns = static_cast<Eigen::Index>(c.model.states().size());
  const auto segments = static_cast<Eigen::Index>(c.segments.size());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(np, np), scores(segments, np);
  std::size_t row = 0;
  for (Eigen::Index b = 0; b < segments; ++b) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(np, np), cross = Eigen::MatrixXd::Zero(np, ns),
                    d = Eigen::MatrixXd::Zero(ns, ns);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(np), jp(np), jx(ns);
    const std::size_t end = row + c.residuals(c.segments[static_cast<std::size_t>(b)]);
    for (; row < end; ++row) {
      jp.setZero();
      jx.setZero();
      for (int k = jacobian.rows[row]; k < jacobian.rows[row + 1]; ++k) {
        const int column = jacobian.cols[static_cast<std::size_t>(k)];
        const double value = jacobian.values[static_cast<std::size_t>(k)];
        if (column < np) {
          jp(column) = value;
        } else {
          jx(column - np - b * ns) = value;
        }
      }
      a.noalias() += jp * jp.transpose();
      cross.noalias() += jp * jx.transpose();
      d.noalias() += jx * jx.transpose();
      g += e[row] * jp;
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> local(d);
    h += local.isInvertible() ? Eigen::MatrixXd(a - cross * local.solve(cross.transpose())) : a;
    scores.row(b) = g.transpose();
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(h);
  if (!lu.isInvertible() || segments < 2) return {};
  const Eigen::MatrixXd centred = scores.rowwise() - scores.colwise().mean();
  const double n = static_cast<double>(segments);
  const Eigen::MatrixXd s = centred.transpose() * centred * (n / (n - 1));
  const Eigen::MatrixXd inverse = lu.inverse();
  return inverse * s * inverse;
}

// The bias that the inputs' white noise gives the refined values (errors in variables), by
// simulation and extrapolation: the refinement again, from `u`, with noise of the same variance
// added to each noisy input (before its low-pass), in RefineOptions::kNoiseReplicates replicates
// of fixed seeds; the bias grows with the noise's variance, so the shift from doubling it is the
// bias at the record's noise. (One Gauss-Newton step from `u` measured a tenth of the shift on a
// lightly damped chain: the refinement is run to its end.) Returns the shift per parameter
// (empty: no input is noisy) and, in `spread`, the covariance of the replicates' mean shift.
std::vector<double> noise_shift(const Comparison& c,
                                const std::vector<std::vector<std::vector<double>>>& raw,
                                const std::vector<InputBand>& bands, const Unknowns& u,
                                int iterations, Eigen::MatrixXd& spread) {
  if (std::none_of(bands.begin(), bands.end(), [](const InputBand& b) { return b.noise_rms > 0; }))
    return {};
  const std::size_t k = RefineOptions::kNoiseReplicates;
  Eigen::MatrixXd shifts(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(u.p.size()));
  for (std::size_t replicate = 0; replicate < k; ++replicate) {
    std::mt19937_64 generator(RefineOptions::kNoiseSeed + replicate);
    std::normal_distribution<double> normal;
    std::vector<std::vector<std::vector<double>>> inputs = raw;
    for (auto& run : inputs) {
      for (const InputBand& band : bands) {
        if (!(band.noise_rms > 0)) continue;
        for (double& value : run[band.index]) value += band.noise_rms * normal(generator);
        if (band.filtered) low_pass(run[band.index], c.record.dt, band);
      }
    }
    Comparison noisy{c.model,   c.record,  c.interpolation, c.substeps, c.segments,
                     c.outputs, c.weights, c.base,          c.names,    {}};
    for (Segment& s : noisy.segments) {
      for (const InputBand& band : bands) {
        const std::vector<double>& x = inputs[s.run][band.index];
        s.inputs[band.index].assign(x.begin() + static_cast<long>(s.first),
                                    x.begin() + static_cast<long>(s.first + s.inputs[0].size()));
      }
    }
    Unknowns v = u;
    minimise(noisy, v, iterations, RefineOptions::kReplicateTolerance);
    for (std::size_t j = 0; j < u.p.size(); ++j) {
      shifts(static_cast<Eigen::Index>(replicate), static_cast<Eigen::Index>(j)) = v.p[j] - u.p[j];
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

  std::vector<std::vector<std::vector<double>>> inputs;
  for (const RecordRun& run : replay.record.runs) {
    inputs.push_back(run_inputs(model, replay.record, run));
  }
  const std::vector<std::vector<std::vector<double>>> raw_inputs = inputs;
  // A held input is taken as exact: its steps hide white noise from the estimate of it.
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    if (replay.interpolation[i] == Interpolation::kHold) continue;
    std::vector<std::vector<double>> runs;
    for (const auto& run : inputs) runs.push_back(run[i]);
    InputBand band = input_band(model.inputs()[i].name, runs, replay.record.dt);
    band.index = i;
    if (band.filtered) {
      for (auto& run : inputs) low_pass(run[i], replay.record.dt, band);
    }
    result.inputs.push_back(band);
  }
  const RecordSimulator start_simulator(model, replay_options.parameters, replay.interpolation,
                                        replay.record.dt, replay.substeps);
  for (std::size_t r = 0; r < replay.record.runs.size(); ++r) {
    const RecordRun& run = replay.record.runs[r];
    const std::size_t rows = run.rows();
    // The segments start from the simulation at the start values: where it still carries its
    // own initial state (a latent state from 0), their initial states would start the search
    // far off, and a strongly nonlinear segment can settle on another solution.
    std::size_t skip = options.skip.value_or(0);
    if (!options.skip && !model.inputs().empty()) {
      skip =
          forgetting_row(start_simulator, run_inputs(model, replay.record, run), replay.initial[r],
                         replay.simulated[r], run_start(run), run_label(replay.record, r))
              .first;
    }
    if (skip >= rows) {
      throw DataError(file_start(replay.record.name),
                      "run " + std::to_string(run_label(replay.record, r)) + " has " +
                          std::to_string(rows) + " rows: none is left to compare after skipping " +
                          std::to_string(skip));
    }
    result.skip.push_back(skip);
  }
  Comparison c{model, replay.record};
  c.interpolation = replay.interpolation;
  c.substeps = replay.substeps;
  c.segments = segments_of(model, replay, inputs, result.skip);
  c.outputs = measured_outputs(model, replay.record);
  c.base = replay_options.parameters;
  c.names = names;
  c.weights.assign(c.outputs.size(), 1.0);
  result.substeps = c.substeps;
  result.segments = c.segments.size();
  result.segment_rows = c.segments.front().rows;
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
  Unknowns u{p, {}};
  for (const Segment& segment : c.segments) u.initial.push_back(segment.initial);
  const std::vector<double> rms_start = output_rms(c, u);
  for (std::size_t o = 0; o < c.outputs.size(); ++o) {
    if (!std::isfinite(rms_start[o])) {
      throw Error("the simulation at the start values fails: validate with them says where");
    }
    c.weights[o] = rms_start[o] > 0 ? 1 / rms_start[o] : 1.0;
  }

  const ceres::Solver::Summary summary =
      minimise(c, u, options.max_iterations, RefineOptions::kTolerance);
  p = u.p;
  result.cost_start = summary.initial_cost;
  result.cost = summary.final_cost;
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.solver = summary.message;
  Eigen::MatrixXd shift_spread;
  // A search that did not converge is doubtful as it is: its noise's bias is not measured.
  const std::vector<double> shift =
      result.converged
          ? noise_shift(c, raw_inputs, result.inputs, u,
                        std::min(options.max_iterations, RefineOptions::kReplicateIterations),
                        shift_spread)
          : std::vector<double>();
  result.noise_replicates = shift.empty() ? 0 : RefineOptions::kNoiseReplicates;

  const std::vector<double> rms = output_rms(c, u);
  for (std::size_t o = 0; o < c.outputs.size(); ++o) {
    result.outputs.push_back(
        {model.variables()[output_variable(model, c.outputs[o])].name, rms_start[o], rms[o]});
  }
  Eigen::MatrixXd covariance = sandwich(c, u);
  if (shift_spread.size() > 0 && covariance.size() > 0) covariance += shift_spread;
  result.dof = static_cast<double>(c.segments.size()) - 1;
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
