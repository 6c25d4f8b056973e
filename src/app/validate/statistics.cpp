#include "app/validate/statistics.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <numeric>
#include <random>

#include "app/validate/fit.hpp"
#include "app/validate/record.hpp"
#include "app/validate/series_statistics.hpp"
#include "solve/distributions.hpp"

namespace momentid {

std::size_t StatisticalValidation::outside() const {
  return static_cast<std::size_t>(std::count_if(
      checks.begin(), checks.end(), [](const StatisticCheck& c) { return !c.inside(); }));
}

namespace {

using Runs = std::vector<std::vector<double>>;  // one series per record run

// The amplitude quantiles compared, and the levels of the crossings in standard deviations
// about the mean: the distribution's body and both tails.
const std::vector<double> kProbabilities = {0.001, 0.01, 0.05, 0.1,  0.25, 0.5,
                                            0.75,  0.9,  0.95, 0.99, 0.999};
const std::vector<double> kLevels = {-2, -1, 0, 1, 2};
// Crossings count with a hysteresis of this many noise standard deviations.
constexpr double kHysteresis = 3;
constexpr std::uint64_t kNoiseSeed = 20261125;

// The largest power of two from kMinSegment to kMaxSegment that leaves kMinSegments segments in
// the shortest run; 0 when none does.
std::size_t segment_length(const Record& record) {
  std::size_t shortest = record.runs.front().rows();
  for (const RecordRun& run : record.runs) shortest = std::min(shortest, run.rows());
  std::size_t segment = 0;
  for (std::size_t s = StatisticalValidation::kMinSegment;
       s <= StatisticalValidation::kMaxSegment &&
       s * StatisticalValidation::kMinSegments <= shortest;
       s *= 2) {
    segment = s;
  }
  return segment;
}

// simulations[k][o]: output o of simulation k, run by run, with white noise of standard
// deviation noise_sd[o] added. Simulation k of run r starts from the replay's state at row
// (k + 1) rows / (kRuns + 1).
std::vector<std::vector<Runs>> simulations(const Model& model, const RecordSimulator& simulator,
                                           const Replay& replay,
                                           const std::vector<std::size_t>& outputs,
                                           const std::vector<double>& noise_sd) {
  const Record& record = replay.record;
  constexpr std::size_t kRuns = StatisticalValidation::kRuns;
  std::vector<std::vector<Runs>> out(kRuns, std::vector<Runs>(outputs.size()));
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const RecordRun& run = record.runs[r];
    const std::vector<std::vector<double>> inputs = run_inputs(model, record, run);
    for (std::size_t k = 0; k < kRuns; ++k) {
      const std::size_t row = (k + 1) * run.rows() / (kRuns + 1);
      std::vector<double> initial;
      for (const std::vector<double>& state : replay.simulated[r]) initial.push_back(state[row]);
      std::vector<std::vector<double>> states =
          simulator.run(inputs, initial, run_start(run), run_label(record, r), run.rows());
      // The measured derivatives (accelerations) after the states, as the outputs number them.
      if (outputs.back() >= states.size()) {
        for (std::vector<double>& d : simulator.derivatives(states, inputs)) {
          states.push_back(std::move(d));
        }
      }
      std::mt19937_64 random(kNoiseSeed + kRuns * r + k);
      for (std::size_t o = 0; o < outputs.size(); ++o) {
        std::vector<double>& series = states[outputs[o]];
        if (noise_sd[o] > 0) {
          std::normal_distribution<double> noise(0.0, noise_sd[o]);
          for (double& x : series) x += noise(random);
        }
        out[k][o].push_back(std::move(series));
      }
    }
  }
  return out;
}

// The record's statistic against the runs' (each a vector over `at`): their mean and range, and
// the distances: the sum of the absolute differences over the sum of the reference (`relative`:
// spectra and rates), or their mean in units of `unit` (quantiles, in the runs' spread).
StatisticCheck check(std::string output, std::string kind, std::vector<double> at,
                     std::vector<double> measured, const std::vector<std::vector<double>>& runs,
                     bool relative, double unit = 1) {
  StatisticCheck c{std::move(output), std::move(kind), std::move(at), std::move(measured)};
  const std::size_t size = c.measured.size();
  const auto k = static_cast<double>(runs.size());
  c.mean.assign(size, 0.0);
  c.low = runs.front();
  c.high = runs.front();
  for (const std::vector<double>& run : runs) {
    for (std::size_t i = 0; i < size; ++i) {
      c.mean[i] += run[i] / k;
      c.low[i] = std::min(c.low[i], run[i]);
      c.high[i] = std::max(c.high[i], run[i]);
    }
  }
  const auto distance = [&](const std::vector<double>& a, const std::vector<double>& reference) {
    double difference = 0, scale = 0;
    for (std::size_t i = 0; i < size; ++i) {
      difference += std::abs(a[i] - reference[i]);
      scale += relative ? std::abs(reference[i]) : unit;
    }
    // A reference of zeros (no run crosses a level) leaves no scale: equal is 0, else out.
    return scale > 0 ? difference / scale : difference > 0 ? HUGE_VAL : 0.0;
  };
  c.distance = distance(c.measured, c.mean);
  for (const std::vector<double>& run : runs) {
    std::vector<double> others(size);
    for (std::size_t i = 0; i < size; ++i) others[i] = (c.mean[i] * k - run[i]) / (k - 1);
    c.run_distances.push_back(distance(run, others));
  }
  return c;
}

// The band of each check: a prediction bound for one more distance from the runs' distances,
// on a logarithmic scale (distances are positive and skewed), at a level that holds for all
// checks together (Bonferroni).
void set_limits(std::vector<StatisticCheck>& checks, double level) {
  const double k = StatisticalValidation::kRuns;
  const double t = student_t_quantile(1 - (1 - level) / static_cast<double>(checks.size()), k - 1);
  for (StatisticCheck& c : checks) {
    // Runs that agree exactly have a distance of 0: the smallest double stands for it.
    std::vector<double> distances;
    for (double d : c.run_distances) distances.push_back(std::max(d, DBL_MIN));
    c.limit = prediction_bound(distances, t);
  }
}

// The three checks of one output.
void add_checks(const std::string& name, const Runs& measured, const std::vector<Runs>& runs,
                double dt, std::size_t segment, double noise_sd,
                std::vector<StatisticCheck>& checks) {
  std::vector<std::vector<double>> psd, quantile, rate;
  double mean = 0, spread = 0;
  for (const Runs& run : runs) {
    const auto [m, s] = mean_and_spread(run);
    mean += m / static_cast<double>(runs.size());
    spread += s / static_cast<double>(runs.size());
  }
  std::vector<double> levels;
  for (double a : kLevels) levels.push_back(mean + a * spread);
  const double hysteresis = kHysteresis * noise_sd;
  for (const Runs& run : runs) {
    psd.push_back(welch_psd(run, dt, segment));
    quantile.push_back(quantiles(run, kProbabilities));
    rate.push_back(upcrossing_rates(run, dt, levels, hysteresis));
  }
  checks.push_back(check(name, "psd", psd_frequencies(dt, segment),
                         welch_psd(measured, dt, segment), psd, true));
  checks.push_back(check(name, "distribution", kProbabilities, quantiles(measured, kProbabilities),
                         quantile, false, spread));
  checks.push_back(check(name, "crossings", levels,
                         upcrossing_rates(measured, dt, levels, hysteresis), rate, true));
}

// The rows a prediction runs ahead: a quarter of the period at the peak of the spectrum `psd`
// (a "psd" check), from 2 rows to kMaxHorizon.
std::size_t prediction_horizon(const StatisticCheck& psd, double dt) {
  constexpr std::size_t kMaxHorizon = 200;
  std::size_t peak = 1;
  for (std::size_t k = 1; k < psd.measured.size(); ++k) {
    if (psd.measured[k] > psd.measured[peak]) peak = k;
  }
  const double quarter = 0.25 / (psd.at[peak] * dt);
  return std::clamp<std::size_t>(static_cast<std::size_t>(std::lround(quarter)), 2, kMaxHorizon);
}

// The prediction errors of one series of states (prediction_fit), each state's rms in units of
// its spread, and the sensor offsets fitted, in the same units; and per state j the slopes of its
// error at the horizon on each state's prediction there (slopes[j][i], in units of spread j over
// spread i): a wrong parameter makes the error follow the states, noise does not.
struct PredictionFit {
  std::vector<double> errors, offsets;
  std::vector<std::vector<double>> slopes;
};

// The model's response started from `states` (per state, run by run) at every `horizon`-th row
// and run `horizon` rows ahead under the record's input, against `states` there. With
// `fit_offsets`, after one constant offset b per state is taken from the states (a sensor offset
// moves both the state a prediction starts from and the states it is compared with): b
// minimises the sum of the states' mean square errors in units of their `spread`. The errors are
// linear in b through r(b) = r + (I - S) b, with S the response's sensitivity to its initial
// state (finite differences), so one least-squares step finds b.
PredictionFit prediction_fit(const Model& model, const RecordSimulator& simulator,
                             const Record& record, const std::vector<Runs>& states,
                             std::size_t horizon, const std::vector<double>& spread,
                             bool fit_offsets) {
  // The interpolation of an input between samples reads up to 24 samples ahead.
  constexpr std::size_t kLookahead = 25;
  constexpr double kStep = 1e-4;  // of a state's spread, for the sensitivities
  const auto k = static_cast<Eigen::Index>(states.size());
  // Per state j, the sums of r_j^2, r_j * m_j and m_j * m_j', m_j the row j of I - S.
  std::vector<double> q(states.size(), 0.0);
  std::vector<Eigen::VectorXd> u(states.size(), Eigen::VectorXd::Zero(k));
  std::vector<Eigen::MatrixXd> p(states.size(), Eigen::MatrixXd::Zero(k, k));
  double count = 0;
  // At the horizon, per state j and i: the sums of e_j x_i and of m_j x_i, x_i the prediction of
  // state i; and of x_i^2.
  std::vector<Eigen::VectorXd> ex(states.size(), Eigen::VectorXd::Zero(k));
  std::vector<Eigen::MatrixXd> mx(states.size(), Eigen::MatrixXd::Zero(k, k));
  Eigen::VectorXd xx = Eigen::VectorXd::Zero(k);
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const RecordRun& run = record.runs[r];
    const std::vector<std::vector<double>> inputs = run_inputs(model, record, run);
    std::vector<std::vector<double>> stretch(inputs.size());
    for (std::size_t start = 0; start + horizon < run.rows(); start += horizon) {
      const std::size_t end = std::min(run.rows(), start + horizon + 1 + kLookahead);
      for (std::size_t i = 0; i < inputs.size(); ++i) {
        stretch[i].assign(inputs[i].begin() + static_cast<std::ptrdiff_t>(start),
                          inputs[i].begin() + static_cast<std::ptrdiff_t>(end));
      }
      std::vector<double> initial;
      for (const Runs& state : states) initial.push_back(state[r][start]);
      const auto predict = [&](const std::vector<double>& from) {
        return simulator.run(stretch, from, run_start(run) + static_cast<double>(start) * record.dt,
                             run_label(record, r), horizon + 1);
      };
      const std::vector<std::vector<double>> predicted = predict(initial);
      std::vector<std::vector<std::vector<double>>> moved;
      for (std::size_t i = 0; i < states.size() && fit_offsets; ++i) {
        std::vector<double> from = initial;
        from[i] += kStep * spread[i];
        moved.push_back(predict(from));
      }
      Eigen::VectorXd x(k);
      for (std::size_t i = 0; i < states.size(); ++i) {
        x(static_cast<Eigen::Index>(i)) = predicted[i][horizon];
      }
      xx += x.cwiseAbs2();
      for (std::size_t n = 1; n <= horizon; ++n) {
        for (std::size_t j = 0; j < states.size(); ++j) {
          const double e = predicted[j][n] - states[j][r][start + n];
          q[j] += e * e;
          if (n == horizon) ex[j] += e * x;
          if (!fit_offsets) continue;
          Eigen::VectorXd m(k);
          for (std::size_t i = 0; i < moved.size(); ++i) {
            const double sensitivity = (moved[i][j][n] - predicted[j][n]) / (kStep * spread[i]);
            m(static_cast<Eigen::Index>(i)) = (i == j ? 1.0 : 0.0) - sensitivity;
          }
          u[j] += e * m;
          p[j] += m * m.transpose();
          if (n == horizon) mx[j] += x * m.transpose();
        }
      }
      count += static_cast<double>(horizon);
    }
  }
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(k);
  for (std::size_t j = 0; j < states.size(); ++j) {
    const double w = 1 / (spread[j] * spread[j]);
    a += w * p[j];
    g += w * u[j];
  }
  Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
  if (fit_offsets) b = a.completeOrthogonalDecomposition().solve(-g);
  if (!b.allFinite()) b.setZero();
  PredictionFit out;
  for (std::size_t j = 0; j < states.size(); ++j) {
    const double square = q[j] + 2 * b.dot(u[j]) + b.dot(p[j] * b);
    out.errors.push_back(std::sqrt(std::max(square, 0.0) / std::max(count, 1.0)) / spread[j]);
    out.offsets.push_back(b(static_cast<Eigen::Index>(j)) / spread[j]);
    std::vector<double> slopes;
    for (std::size_t i = 0; i < states.size(); ++i) {
      const auto at = static_cast<Eigen::Index>(i);
      const double sum = ex[j](at) + mx[j].row(at).dot(b);
      slopes.push_back(xx(at) > 0 ? sum / xx(at) * spread[i] / spread[j] : 0.0);
    }
    out.slopes.push_back(std::move(slopes));
  }
  return out;
}

// The prediction checks of each state: the record's prediction error (prediction_fit), the
// runs' own as the distances that set the band; and the bias check, the slopes of the error at
// the horizon on the states' predictions against the runs' (a stiffness 10% off leaves the rms
// error of a noisy record inside its band, but makes the error follow the states). Each distance
// is floored at kPredictionFloor: below it the difference is the integrators', not the models'.
// `psd`: the first state's spectrum check.
void add_prediction_checks(const Model& model, const RecordSimulator& simulator,
                           const Record& record, const std::vector<Runs>& measured,
                           const std::vector<std::vector<Runs>>& runs, const StatisticCheck& psd,
                           std::vector<StatisticCheck>& checks) {
  constexpr double kPredictionFloor = 1e-3;
  std::vector<double> spread;
  for (const Runs& state : measured) {
    spread.push_back(std::max(mean_and_spread(state).second, DBL_MIN));
  }
  const std::size_t horizon = prediction_horizon(psd, record.dt);
  const PredictionFit fit =
      prediction_fit(model, simulator, record, measured, horizon, spread, true);
  const std::vector<double>& own = fit.errors;
  // The runs have no offset. Fitting the record's few constants over its many predicted rows
  // lowers its mean square error by only about (states / rows) of it, so the runs' errors,
  // unfitted, set the band at a fraction of the cost.
  std::vector<PredictionFit> of_runs;
  for (const std::vector<Runs>& run : runs) {
    of_runs.push_back(prediction_fit(model, simulator, record, run, horizon, spread, false));
  }
  const auto floored = [&](StatisticCheck& c) {
    c.distance = std::max(c.distance, kPredictionFloor);
    for (double& d : c.run_distances) d = std::max(d, kPredictionFloor);
  };
  const double ahead = static_cast<double>(horizon) * record.dt;
  for (std::size_t j = 0; j < measured.size(); ++j) {
    std::vector<std::vector<double>> errors, slopes;
    for (const PredictionFit& run : of_runs) {
      errors.push_back({run.errors[j]});
      slopes.push_back(run.slopes[j]);
    }
    StatisticCheck c =
        check(model.states()[j].name, "prediction", {ahead}, {own[j]}, errors, false);
    c.distance = own[j];
    c.offset = fit.offsets[j];
    c.run_distances.clear();
    for (const std::vector<double>& e : errors) c.run_distances.push_back(e[0]);
    floored(c);
    checks.push_back(std::move(c));
    std::vector<double> index(measured.size());
    std::iota(index.begin(), index.end(), 0.0);
    StatisticCheck bias =
        check(model.states()[j].name, "bias", std::move(index), fit.slopes[j], slopes, false);
    floored(bias);
    checks.push_back(std::move(bias));
  }
}

}  // namespace

StatisticalValidation compare_statistics(const Model& model, const RecordSimulator& simulator,
                                         const Replay& replay,
                                         const std::vector<std::size_t>& outputs) {
  StatisticalValidation out;
  const Record& record = replay.record;
  out.segment = segment_length(record);
  if (out.segment == 0) {
    out.not_compared =
        "a run of fewer than " +
        std::to_string(StatisticalValidation::kMinSegment * StatisticalValidation::kMinSegments) +
        " rows is too short for the spectra";
    return out;
  }
  out.compared = true;
  out.runs = StatisticalValidation::kRuns;
  out.level = StatisticalValidation::kLevel;
  std::vector<Runs> measured;
  for (std::size_t j : outputs) {
    const auto column = static_cast<std::size_t>(record.column_of(output_variable(model, j)));
    Runs series;
    for (const RecordRun& run : record.runs) series.push_back(run.columns[column]);
    out.noise_sd.push_back(std::sqrt(white_noise_variance(series, replay.holds_an_input())));
    measured.push_back(std::move(series));
  }
  const std::vector<std::vector<Runs>> runs =
      simulations(model, simulator, replay, outputs, out.noise_sd);
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    std::vector<Runs> of_output;
    for (const std::vector<Runs>& run : runs) of_output.push_back(run[o]);
    add_checks(model.variables()[output_variable(model, outputs[o])].name, measured[o], of_output,
               record.dt, out.segment, out.noise_sd[o], out.checks);
  }
  // With every state measured (the first outputs, in order), the response predicted a short time
  // ahead from the measured state: what a wrong parameter changes even where the trajectory
  // cannot be reproduced.
  const std::size_t states = model.states().size();
  bool every_state = outputs.size() >= states;
  for (std::size_t o = 0; o < states && every_state; ++o) every_state = outputs[o] == o;
  if (every_state) {
    const StatisticCheck psd = out.checks.front();  // a copy: the checks grow
    const auto first = [&](const std::vector<Runs>& all) {
      return std::vector<Runs>(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(states));
    };
    std::vector<std::vector<Runs>> state_runs;
    for (const std::vector<Runs>& run : runs) state_runs.push_back(first(run));
    add_prediction_checks(model, simulator, record, first(measured), state_runs, psd, out.checks);
  }
  set_limits(out.checks, out.level);
  return out;
}

}  // namespace momentid
