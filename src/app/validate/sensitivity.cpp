#include "app/validate/sensitivity.hpp"

#include <cmath>
#include <limits>

#include "app/validate/record.hpp"
#include "app/validate/series_statistics.hpp"

namespace momentid {
namespace {

constexpr double kFloor = 1e-6;

// The separation of the perturbed simulation of run r from the replay's, row by row.
std::vector<double> separation(const Model& model, const RecordSimulator& simulator,
                               const Replay& replay, std::size_t r) {
  const Record& record = replay.record;
  const std::vector<std::vector<double>>& simulated = replay.simulated[r];
  const std::size_t states = simulated.size(), rows = record.runs[r].rows();
  std::vector<double> spread(states, 1.0), perturbed = replay.initial[r];
  for (std::size_t j = 0; j < states; ++j) {
    const double sd = mean_and_spread({simulated[j]}).second;
    if (sd > 0 && std::isfinite(sd)) spread[j] = sd;
    perturbed[j] += Sensitivity::kPerturbation * spread[j];
  }
  std::vector<std::vector<double>> other;
  try {
    other = simulator.run(run_inputs(model, record, record.runs[r]), perturbed,
                          run_start(record.runs[r]), run_label(record, r), rows);
  } catch (const Error&) {
    return {std::numeric_limits<double>::infinity()};
  }
  std::vector<double> out(rows);
  for (std::size_t n = 0; n < rows; ++n) {
    double sum = 0;
    for (std::size_t j = 0; j < states; ++j) {
      const double d = (other[j][n] - simulated[j][n]) / spread[j];
      sum += d * d;
    }
    out[n] = std::sqrt(sum / static_cast<double>(states));
  }
  return out;
}

Sensitivity summary(const std::vector<double>& distance, double dt) {
  Sensitivity out;
  std::size_t end = distance.size() - 1;
  for (std::size_t n = 0; n < distance.size(); ++n) {
    if (!(distance[n] <= out.separation)) out.separation = distance[n];
    if (!(distance[n] < Sensitivity::kSpread) && !out.time_to_spread) {
      out.time_to_spread = static_cast<double>(n) * dt;
      end = n;
    }
  }
  out.final_separation = distance.back();
  out.sensitive = out.time_to_spread.has_value();
  // A separation that shrinks meets rounding (about 1e-16 of the spread) and may become 0: the
  // exponent is measured until it falls below 1e-6 of its start, well above rounding.
  for (std::size_t n = 0; !out.sensitive && n < distance.size(); ++n) {
    if (distance[n] < kFloor * Sensitivity::kPerturbation) {
      end = n;
      break;
    }
  }
  const double reached = std::max(distance[end], std::numeric_limits<double>::min());
  const double time = std::max(static_cast<double>(end), 1.0) * dt;
  out.lyapunov = std::log(reached / Sensitivity::kPerturbation) / time;
  return out;
}

}  // namespace

Sensitivity measure_sensitivity(const Model& model, const RecordSimulator& simulator,
                                const Replay& replay) {
  Sensitivity worst;
  worst.separation = -1;
  for (std::size_t r = 0; r < replay.record.runs.size(); ++r) {
    Sensitivity run = summary(separation(model, simulator, replay, r), replay.record.dt);
    run.run = run_label(replay.record, r);
    if (run.separation > worst.separation) worst = run;
  }
  return worst;
}

}  // namespace momentid
