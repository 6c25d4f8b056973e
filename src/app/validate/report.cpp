// The text and JSON reports of validate.

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/validate/record.hpp"
#include "app/validate/report_statistics.hpp"
#include "common/decimal.hpp"
#include "common/json.hpp"
#include "common/number.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/json.hpp"
#include "momentid/validate.hpp"

namespace momentid {
namespace {

std::string parameters_text(const ValidateResult& r) {
  std::string out;
  for (std::size_t p = 0; p < r.model->parameters().size(); ++p) {
    const std::string& name = r.model->parameters()[p].name;
    if (p > 0) out += ", ";
    out += name + "=" + shortest_decimal(r.parameters.at(name).value);
  }
  return out;
}

std::string skip_text(const ValidateResult& r, bool autonomous) {
  const auto [low, high] = std::minmax_element(r.skip.begin(), r.skip.end());
  std::string rows =
      *low == *high ? std::to_string(*low) : std::to_string(*low) + " to " + std::to_string(*high);
  std::string out = "the first " + rows + " rows of each run";
  if (r.skip_chosen && autonomous) {
    out +=
        " (the model has no input: its response is that to the initial state, which is "
        "compared whole)";
  } else if (r.skip_chosen) {
    out +=
        " (until a perturbation of the initial state by 10% of each state's spread fell "
        "below 1% of its size)";
  }
  return out;
}

// A check outside its band blames the model, unless the trajectory cannot be reproduced.
std::string check_text(const CorrelationCheck& c, bool sensitive) {
  const int last = c.first_lag + static_cast<int>(c.values.size()) - 1;
  std::string out = c.with.empty() ? "autocorrelation of the error"
                                   : "cross-correlation of the error with " + c.with;
  out += ", lags " + std::to_string(c.first_lag) + ".." + std::to_string(last) + ": " +
         std::to_string(c.outside()) + " of " + std::to_string(c.values.size()) + " outside +-" +
         number(c.band, "%.3g");
  if (c.outside() == 0) return out;
  std::size_t worst = 0;
  for (std::size_t k = 0; k < c.values.size(); ++k) {
    if (std::abs(c.values[k]) > std::abs(c.values[worst])) worst = k;
  }
  out += " (largest " + number(c.values[worst], "%.3g") + " at lag " +
         std::to_string(c.first_lag + static_cast<int>(worst)) + ")  <- " +
         (sensitive        ? "expected of a trajectory that cannot be reproduced"
          : c.with.empty() ? "not white: the model leaves structure in the error"
                           : "the error depends on the input: the model misses part of its effect");
  return out;
}

// The noise band's section: a line per output, or why it was not compared (nothing for a
// sensitive model, whose statistics judge it).
std::string noise_band_text(const ValidateResult& r) {
  const NoiseBand& band = r.noise_band;
  if (r.sensitivity.sensitive) return "";
  if (!band.compared) return "noise band: not compared: " + band.not_compared + "\n\n";
  std::string out =
      "noise band (the error's rms beyond its white noise, the median over "
      "segments, against " +
      std::to_string(band.outputs.front().simulations.size()) +
      " simulations with the inputs' noise added (";
  for (std::size_t i = 0; i < band.input_noise.size(); ++i) {
    const bool held = r.replay.interpolation[i] == Interpolation::kHold;
    out += (i ? ", " : "") + r.model->inputs()[i].name + " " +
           (held ? "held: exact" : number(band.input_noise[i], "%.3g"));
  }
  out += std::string(")") + (band.with_errors ? " and the estimates' errors" : "") + "; " +
         number(100 * band.level, "%g") + "% band for all " + std::to_string(band.outputs.size()) +
         " together):\n";
  for (const NoiseBand::Output& o : band.outputs) {
    const auto [low, high] = std::minmax_element(o.simulations.begin(), o.simulations.end());
    out += "  " + o.name + ": " + number(o.error, "%.4g") + " (simulations " +
           number(*low, "%.3g") + " to " + number(*high, "%.3g") +
           (band.with_errors ? ", the estimates' errors " + number(o.estimates, "%.3g") : "") +
           ", limit " + number(o.limit, "%.3g") + ")" +
           (o.inside() ? "" : "  <- " + number(o.error / o.limit, "%.3g") + " times the limit") +
           "\n";
  }
  return out + "\n";
}

}  // namespace

std::string format_text(const ValidateResult& r) {
  const AlgebraLock lock;
  const Replay& replay = r.replay;
  const Record& record = replay.record;
  const Model& model = *r.model;
  std::size_t rows = 0;
  for (const RecordRun& run : record.runs) rows += run.rows();
  std::string out = "validate " + model.name() + " on " + record.name + ": " +
                    std::to_string(rows) + " rows in " + std::to_string(record.runs.size()) +
                    (record.runs.size() == 1 ? " run" : " runs") +
                    ", dt = " + number(record.dt, "%g") + "\n";
  out += "parameters (" + r.parameters_from + "): " + parameters_text(r) + "\n";
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    out += "input " + model.inputs()[i].name + ": " + to_string(replay.interpolation[i]) +
           " between samples\n";
  }
  const bool converged =
      replay.substeps_chosen && replay.substep_change < ReplayOptions::kSubstepTolerance;
  out += "integration: " + std::to_string(replay.substeps) + " Runge-Kutta step" +
         (replay.substeps == 1 ? "" : "s") + " per sample" +
         (converged ? " (halving the step changes the simulation by less than 1e-6 of each "
                      "state's spread)"
                    : "") +
         "\n";
  out += "initial state (run " + std::to_string(run_label(record, 0)) + "): ";
  for (std::size_t j = 0; j < model.states().size(); ++j) {
    out += (j ? ", " : "") + model.states()[j].name + " = " + number(replay.initial[0][j], "%.6g") +
           " from " + replay.initial_how[j];
  }
  out += "\nskipped: " + skip_text(r, model.inputs().empty()) + "\n";
  if (!r.centered.empty()) {
    out += "means removed (--center):";
    for (const auto& [name, mean] : r.centered) out += " " + name + " " + number(mean, "%.4g");
    out += "\n";
  }
  out += sensitivity_text(r) + "\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-10s %10s %12s %9s %14s %12s\n", "output", "samples",
                "rms error", "fit %", "rms first 10%", "rms rest");
  out += line;
  for (const OutputFit& f : r.outputs) {
    std::snprintf(line, sizeof line, "%-10s %10zu %12.5g %9s %14.5g %12s\n", f.name.c_str(),
                  f.samples, f.rms, number(f.fit, "%.3f").c_str(), f.rms_start,
                  number(f.rms_rest, "%.5g").c_str());
    out += line;
  }
  out += "\ncorrelation checks (99% bands):\n";
  for (const OutputFit& f : r.outputs) {
    if (!f.autocorrelation) {
      out += "  " + f.name + ": the error is zero throughout: nothing to check\n";
      continue;
    }
    const bool sensitive = r.sensitivity.sensitive;
    out += "  " + f.name + ": " + check_text(*f.autocorrelation, sensitive) + "\n";
    for (const CorrelationCheck& c : f.cross) {
      out += "  " + f.name + ": " + check_text(c, sensitive) + "\n";
    }
  }
  out += "\n" + noise_band_text(r);
  out += statistics_text(r);
  if (r.warnings.empty()) out += "warnings: none\n";
  for (const std::string& w : r.warnings) out += "warning: " + w + "\n";
  return out;
}

namespace {

using Json = nlohmann::ordered_json;

Json noise_band_json(const NoiseBand& band, const Model& model) {
  Json out = {{"compared", band.compared}, {"not_compared", band.not_compared}};
  Json& noise = out["input_noise"] = Json::object();
  for (std::size_t i = 0; i < band.input_noise.size(); ++i) {
    noise[model.inputs()[i].name] = json_value(band.input_noise[i]);
  }
  out["with_errors"] = band.with_errors;
  out["level"] = band.level;
  Json& outputs = out["outputs"] = Json::object();
  for (const NoiseBand::Output& o : band.outputs) {
    outputs[o.name] = {{"error", json_value(o.error)},
                       {"simulations", json_value(o.simulations)},
                       {"estimates", json_value(o.estimates)},
                       {"limit", json_value(o.limit)},
                       {"inside", o.inside()}};
  }
  return out;
}

Json check_json(const CorrelationCheck& c) {
  Json lags = Json::array();
  for (std::size_t k = 0; k < c.values.size(); ++k) {
    lags.push_back(c.first_lag + static_cast<int>(k));
  }
  return {{"lags", std::move(lags)},
          {"values", json_value(c.values)},
          {"band99", json_value(c.band)},
          {"outside", c.outside()}};
}

Json output_json(const OutputFit& f) {
  Json cross = Json::object();
  for (const CorrelationCheck& c : f.cross) cross[c.with] = check_json(c);
  return {{"samples", f.samples},
          {"rms", json_value(f.rms)},
          {"fit_percent", json_value(f.fit)},
          {"rms_first_10pct", json_value(f.rms_start)},
          {"rms_rest", json_value(f.rms_rest)},
          {"autocorrelation", f.autocorrelation ? check_json(*f.autocorrelation) : Json()},
          {"cross_correlation", std::move(cross)}};
}

// {state: value} per run, and {state: how it was found}.
void initial_state_json(Json& out, const ValidateResult& r) {
  const auto& states = r.model->states();
  Json& initial = out["initial_state"] = Json::array();
  for (const std::vector<double>& run : r.replay.initial) {
    Json values = Json::object();
    for (std::size_t j = 0; j < states.size(); ++j) values[states[j].name] = json_value(run[j]);
    initial.push_back(std::move(values));
  }
  Json& how = out["initial_how"] = Json::object();
  for (std::size_t j = 0; j < states.size(); ++j) how[states[j].name] = r.replay.initial_how[j];
}

}  // namespace

nlohmann::ordered_json json_value(const ValidateResult& r) {
  const AlgebraLock lock;
  const Replay& replay = r.replay;
  const Record& record = replay.record;
  const Model& model = *r.model;
  std::size_t rows = 0;
  for (const RecordRun& run : record.runs) rows += run.rows();
  Json out = {
      {"model", model.name()},      {"data", record.name},         {"rows", rows},
      {"runs", record.runs.size()}, {"dt", json_value(record.dt)}, {"parameters", Json::object()}};
  for (const Declaration& p : model.parameters()) {
    out["parameters"][p.name] = json_value(r.parameters.at(p.name).value);
  }
  out["parameters_from"] = r.parameters_from;
  Json& interpolation = out["interpolation"] = Json::object();
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    interpolation[model.inputs()[i].name] = to_string(replay.interpolation[i]);
  }
  out["substeps"] = replay.substeps;
  initial_state_json(out, r);
  out["skip"] = r.skip;
  out["skip_chosen"] = r.skip_chosen;
  if (!r.centered.empty()) {
    Json& centered = out["centered"] = Json::object();
    for (const auto& [name, mean] : r.centered) centered[name] = json_value(mean);
  }
  Json& outputs = out["outputs"] = Json::object();
  for (const OutputFit& f : r.outputs) outputs[f.name] = output_json(f);
  out["noise_band"] = noise_band_json(r.noise_band, model);
  statistics_json(out, r);
  out["warnings"] = r.warnings;
  return out;
}

std::string format_json(const ValidateResult& r) { return json_text(json_value(r)); }

}  // namespace momentid
