#include "app/validate/noise_band.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "app/validate/fit.hpp"
#include "app/validate/record.hpp"
#include "app/validate/series_statistics.hpp"
#include "solve/distributions.hpp"

namespace momentid {
namespace {

constexpr std::uint64_t kSeed = 20261129;
using Runs = std::vector<std::vector<double>>;

// The typical mean square of a series' smooth part: the median over segments of kSegmentRows
// rows or more (kSegments per run at most) of their mean square about the series' mean, less
// the series' white noise variance; negative where the white noise's estimate exceeds it. The
// median, because an input's noise moves a lightly damped response in bursts, which leave most
// segments alone, where a wrong model errs in all of them.
double smooth_square(const Runs& runs, bool held) {
  constexpr std::size_t kSegments = 16, kSegmentRows = 512;
  const double mean = mean_and_spread(runs).first, white = white_noise_variance(runs, held);
  std::vector<double> squares;
  for (const std::vector<double>& run : runs) {
    const std::size_t count = std::clamp<std::size_t>(run.size() / kSegmentRows, 1, kSegments);
    for (std::size_t s = 0; s < count; ++s) {
      const std::size_t from = run.size() * s / count, to = run.size() * (s + 1) / count;
      double sum = 0;
      for (std::size_t n = from; n < to; ++n) sum += (run[n] - mean) * (run[n] - mean);
      if (to > from) squares.push_back(sum / static_cast<double>(to - from));
    }
  }
  if (squares.empty()) return 0;
  const auto middle = squares.begin() + static_cast<std::ptrdiff_t>(squares.size() / 2);
  std::nth_element(squares.begin(), middle, squares.end());
  return *middle - white;
}

// The rms that a smooth mean square stands for (0 for one that is not positive).
double root(double square) { return std::sqrt(std::max(square, 0.0)); }

// White noise added to each input: of standard deviation sd[i] on input i, drawn from `random`.
struct InputNoise {
  const std::vector<double>& sd;
  std::mt19937_64& random;
};

// One more replay with the parameters `values`, the inputs as recorded or with `noise` added;
// per output, its difference from the replay over the compared rows, run by run. Throws Error
// when it blows up.
std::vector<Runs> replay_again(const Model& model, const ParameterValues& values,
                               const Replay& replay, const std::vector<std::size_t>& skip,
                               const std::vector<std::size_t>& outputs,
                               const InputNoise* noise = nullptr) {
  const Record& record = replay.record;
  const RecordSimulator simulator(model, values, replay.interpolation, record.dt, replay.substeps);
  const std::size_t states = model.states().size();
  std::vector<Runs> out(outputs.size(), Runs(record.runs.size()));
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const RecordRun& run = record.runs[r];
    std::vector<std::vector<double>> inputs = run_inputs(model, record, run);
    for (std::size_t i = 0; noise && i < inputs.size(); ++i) {
      if (!(noise->sd[i] > 0)) continue;
      std::normal_distribution<double> draw(0.0, noise->sd[i]);
      for (double& x : inputs[i]) x += draw(noise->random);
    }
    const std::vector<std::vector<double>> simulated =
        simulator.run(inputs, replay.initial[r], run_start(run), run_label(record, r), run.rows());
    std::vector<std::vector<double>> derivatives;
    if (!model.measured_derivatives().empty()) {
      derivatives = simulator.derivatives(simulated, inputs);
    }
    for (std::size_t o = 0; o < outputs.size(); ++o) {
      const std::size_t j = outputs[o];
      const std::vector<double>& again = j < states ? simulated[j] : derivatives[j - states];
      const std::vector<double>& before = simulated_output(model, replay, r, j);
      for (std::size_t n = skip[r]; n < again.size(); ++n) {
        out[o][r].push_back(again[n] - before[n]);
      }
    }
  }
  return out;
}

// A replay's differences over the compared rows of an output, run by run (`lengths`; empty
// `differences`: zeros, the replay unchanged), with white noise of standard deviation `sd`.
Runs with_white_noise(Runs differences, double sd, const std::vector<std::size_t>& lengths,
                      std::mt19937_64& random) {
  if (differences.empty()) {
    for (std::size_t length : lengths) differences.emplace_back(length, 0.0);
  }
  if (!(sd > 0)) return differences;
  std::normal_distribution<double> noise(0.0, sd);
  for (std::vector<double>& run : differences) {
    for (double& x : run) x += noise(random);
  }
  return differences;
}

// Whether a covariance can widen the band: not empty, finite, not 0.
bool usable(const std::vector<std::vector<double>>& covariance) {
  bool finite = !covariance.empty(), nonzero = false;
  for (const std::vector<double>& row : covariance) {
    for (double c : row) {
      finite = finite && std::isfinite(c);
      nonzero = nonzero || c != 0;
    }
  }
  return finite && nonzero;
}

// Per output, the root of the q-quantile of the mean square that the estimates' errors leave in
// it: with the sensitivities D of the output to the parameters (by a replay with each one
// standard error away), the mean square of D d for d ~ N(0, covariance) is a sum of chi-squares
// of one degree of freedom weighted by the eigenvalues of G C (G the sensitivities' covariance
// over the compared rows), taken as c chi-square(nu) with the same mean and variance
// (Satterthwaite).
std::vector<double> estimate_errors(const Model& model, const ParameterValues& parameters,
                                    const std::vector<std::vector<double>>& covariance,
                                    const Replay& replay, const std::vector<std::size_t>& skip,
                                    const std::vector<std::size_t>& outputs, double q) {
  std::vector<std::size_t> free;
  for (std::size_t p = 0; p < covariance.size(); ++p) {
    if (covariance[p][p] > 0) free.push_back(p);
  }
  const auto n = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd c(n, n);
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) {
      c(a, b) = covariance[free[static_cast<std::size_t>(a)]][free[static_cast<std::size_t>(b)]];
    }
  }
  // sensitivity[o](row, a): output o's change per unit of parameter free[a].
  std::vector<Eigen::MatrixXd> sensitivity(outputs.size());
  for (Eigen::Index a = 0; a < n; ++a) {
    const std::size_t p = free[static_cast<std::size_t>(a)];
    const std::string& name = model.parameters()[p].name;
    const double step = std::sqrt(covariance[p][p]);
    ParameterValues moved = parameters;
    moved[name] = parameters.at(name).value + step;
    const std::vector<Runs> differences = replay_again(model, moved, replay, skip, outputs);
    for (std::size_t o = 0; o < outputs.size(); ++o) {
      std::size_t rows = 0;
      for (const std::vector<double>& run : differences[o]) rows += run.size();
      if (a == 0) sensitivity[o].resize(static_cast<Eigen::Index>(rows), n);
      Eigen::Index row = 0;
      for (const std::vector<double>& run : differences[o]) {
        for (double d : run) sensitivity[o](row++, a) = d / step;
      }
    }
  }
  std::vector<double> out;
  for (Eigen::MatrixXd& d : sensitivity) {
    d.rowwise() -= d.colwise().mean();
    const Eigen::MatrixXd gc = (d.transpose() * d / static_cast<double>(d.rows())) * c;
    const double mean = gc.trace(), squares = (gc * gc).trace();
    if (!(mean > 0) || !(squares > 0)) {
      out.push_back(0);
      continue;
    }
    const double dof = mean * mean / squares;
    out.push_back(std::sqrt(squares / mean * chi_square_quantile(q, dof)));
  }
  return out;
}

}  // namespace

std::size_t NoiseBand::outside() const {
  return static_cast<std::size_t>(
      std::count_if(outputs.begin(), outputs.end(), [](const Output& o) { return !o.inside(); }));
}

NoiseBand compare_noise_band(const Model& model, const ParameterValues& parameters,
                             const std::vector<std::vector<double>>& covariance,
                             const Replay& replay, const std::vector<std::size_t>& skip,
                             const std::vector<std::size_t>& outputs,
                             const std::vector<ComparedRows>& rows) {
  const Record& record = replay.record;
  const bool held = replay.holds_an_input();
  NoiseBand band;
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    // A held input is the sequence of values that drove the system (a generator's, a DAC's):
    // exact. A sampled one is a sensor's signal, with its noise.
    if (replay.interpolation[i] == Interpolation::kHold) {
      band.input_noise.push_back(0);
      continue;
    }
    Runs column;
    const auto at = static_cast<std::size_t>(record.column_of(model.states().size() + i));
    for (const RecordRun& run : record.runs) column.push_back(run.columns[at]);
    band.input_noise.push_back(std::sqrt(white_noise_variance(column, held)));
  }
  // The record's error per output, the white noise each simulation carries alike, the floor.
  std::vector<double> white, floor;
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    NoiseBand::Output output;
    output.name = model.variables()[output_variable(model, outputs[o])].name;
    output.error = root(smooth_square(rows[o].error, held));
    band.outputs.push_back(std::move(output));
    white.push_back(std::sqrt(white_noise_variance(rows[o].error, held)));
    floor.push_back(NoiseBand::kFloor * mean_and_spread(rows[o].measured).second);
  }
  // The inputs' noise: replays with it (with every input held, none: they would not differ).
  const bool noisy = std::any_of(band.input_noise.begin(), band.input_noise.end(),
                                 [](double sd) { return sd > 0; });
  std::vector<std::size_t> lengths;
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    lengths.push_back(record.runs[r].rows() - skip[r]);
  }
  std::vector<std::vector<double>> simulations;  // per simulation, per output: smooth_square
  for (std::size_t k = 0; k < NoiseBand::kSimulations; ++k) {
    std::mt19937_64 random(kSeed + k);
    const InputNoise noise{band.input_noise, random};
    std::vector<Runs> differences(outputs.size());
    try {
      if (noisy) {
        differences = replay_again(model, parameters, replay, skip, outputs, &noise);
      }
    } catch (const Error&) {
      continue;
    }
    std::vector<double>& square = simulations.emplace_back();
    for (std::size_t o = 0; o < outputs.size(); ++o) {
      square.push_back(smooth_square(
          with_white_noise(std::move(differences[o]), white[o], lengths, random), held));
    }
  }
  if (2 * simulations.size() < NoiseBand::kSimulations) {
    band.not_compared = std::to_string(NoiseBand::kSimulations - simulations.size()) + " of " +
                        std::to_string(NoiseBand::kSimulations) +
                        " replays with the inputs' noise blow up";
    return band;
  }
  const double q = 1 - (1 - NoiseBand::kLevel) / static_cast<double>(outputs.size());
  std::vector<double> errors(outputs.size(), 0.0);
  if (usable(covariance)) {
    try {
      errors = estimate_errors(model, parameters, covariance, replay, skip, outputs, q);
    } catch (const Error&) {
      band.not_compared =
          "the model blows up with a parameter one standard error from its estimate: the "
          "estimates are too uncertain for the model to be simulated";
      return band;
    }
    band.with_errors = true;
  }
  band.compared = true;
  band.level = NoiseBand::kLevel;
  const double t = student_t_quantile(q, static_cast<double>(simulations.size()) - 1);
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    NoiseBand::Output& output = band.outputs[o];
    std::vector<double> squares;
    for (const std::vector<double>& square : simulations) {
      squares.push_back(square[o]);
      output.simulations.push_back(root(square[o]));
    }
    output.estimates = errors[o];
    const double noise = std::max(prediction_bound(squares, t), floor[o] * floor[o]);
    output.limit = std::sqrt(noise + errors[o] * errors[o]);
  }
  return band;
}

}  // namespace momentid
