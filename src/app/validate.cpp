#include "momentid/validate.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>

#include "app/validate/fit.hpp"
#include "app/validate/noise_band.hpp"
#include "app/validate/record.hpp"
#include "app/validate/replay.hpp"
#include "app/validate/residuals.hpp"
#include "app/validate/sensitivity.hpp"
#include "app/validate/statistics.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/data_pass.hpp"
#include "momentid/error.hpp"

// validate: replay the record (validate/replay.cpp), measure how fast nearby trajectories
// separate (validate/sensitivity.cpp), choose the rows to skip, then compare each measured state
// (validate/fit.cpp) and test its error (validate/residuals.cpp); for a sensitive model, whose
// trajectory cannot be reproduced, compare the response's statistics (validate/statistics.cpp).
// The reports are in validate/report.cpp and validate/report_statistics.cpp.

namespace momentid {

void ValidateOptions::validate() const {
  if (lags < 1 || lags > kMaxLags) {
    throw UsageError("lags", "expected a number from 1 to " + std::to_string(kMaxLags) +
                                 ", found " + std::to_string(lags));
  }
}

namespace {

std::string substep_warning(const Replay& replay) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2g", replay.substep_change);
  return "even " + std::to_string(replay.substeps) +
         " Runge-Kutta steps per sample change the simulation by " + text +
         " of its spread when halved: the sample interval is too coarse for the model's fastest "
         "dynamics with these values, and the simulation error is part of the fit";
}

// The rows left out at the start of each run (ValidateResult::skip), with a warning for a run
// whose simulation never forgets its initial state unless the model is sensitive (which says
// more).
void choose_skips(const Model& model, const RecordSimulator& simulator,
                  const ValidateOptions& options, ValidateResult& result) {
  const Replay& replay = result.replay;
  const Record& record = replay.record;
  result.skip_chosen = !options.skip;
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const std::size_t rows = record.runs[r].rows();
    std::size_t skip = 0;
    if (options.skip) {
      skip = *options.skip;
    } else if (!model.inputs().empty()) {
      const auto [row, distance] =
          forgetting_row(simulator, run_inputs(model, record, record.runs[r]), replay.initial[r],
                         replay.simulated[r], run_start(record.runs[r]), run_label(record, r));
      skip = row;
      if (distance > 0.01 && !result.sensitivity.sensitive) {
        char text[64];
        std::snprintf(text, sizeof text, "%.3g%%", 100 * distance);
        result.warnings.push_back(
            "run " + std::to_string(run_label(record, r)) +
            ": the simulation still depends on its initial state after half the run (a "
            "perturbation of 10% of each state's spread is still at " +
            text +
            " of its size): the model is barely damped, unstable or chaotic with these values, "
            "and the fit reflects its start as much as its parameters");
      }
    }
    if (skip >= rows) {
      throw DataError(file_start(record.name),
                      "run " + std::to_string(run_label(record, r)) + " has " +
                          std::to_string(rows) + " rows: none is left to compare after skipping " +
                          std::to_string(skip));
    }
    result.skip.push_back(skip);
  }
}

// A warning for each output outside its noise band, which makes the result inconsistent; one
// for a band that could not be compared.
void add_band_warnings(const NoiseBand& band, ValidateResult& result) {
  if (result.sensitivity.sensitive) return;
  if (!band.compared) {
    result.warnings.push_back("the noise band is not compared: " + band.not_compared);
    return;
  }
  const std::string explained =
      band.with_errors ? "the inputs' noise and the estimates' errors" : "the inputs' noise";
  for (const NoiseBand::Output& output : band.outputs) {
    if (output.inside()) continue;
    char ratio[32];
    std::snprintf(ratio, sizeof ratio, "%.3g", output.error / output.limit);
    result.warnings.push_back(
        output.name + ": the error beyond its white noise is " + ratio + " times what " +
        explained + " can leave (the noise band): the model or its parameters are wrong" +
        (band.with_errors ? ""
                          : ", or the values simulated with are not exact (give the estimates' "
                            "file, whose errors widen the band)"));
    result.consistent = false;
  }
}

// The overall verdict: the statistics judge a sensitive model, the trajectory fit any other
// (whose warnings have set `consistent`).
void judge(ValidateResult& result) {
  const std::string cannot =
      "the trajectory cannot be reproduced (the model is sensitive to its initial state under "
      "this input): ";
  if (!result.sensitivity.sensitive) {
    result.verdict = "the trajectory can be reproduced and its fit judges the model: ";
    if (result.consistent) {
      result.verdict += result.noise_band.compared
                            ? "every output's error is what the noise leaves (the noise band)"
                            : "no output is worse than its mean or drifts";
    } else {
      result.verdict += "the warnings say where it fails";
      if (result.statistics.compared) {
        result.verdict += ", and " + std::to_string(result.statistics.outside()) + " of " +
                          std::to_string(result.statistics.checks.size()) +
                          " statistics of the response are outside their bands";
      }
    }
    return;
  }
  const StatisticalValidation& s = result.statistics;
  if (!s.compared) {
    // Neither the trajectory nor the statistics judged the model: not shown consistent.
    result.consistent = false;
    result.verdict =
        cannot + "nothing judges it, since its statistics are not compared: " + s.not_compared;
    return;
  }
  const std::string count = std::to_string(s.checks.size());
  result.consistent = s.outside() == 0;
  if (result.consistent) {
    result.verdict = cannot + "its statistics judge it, and all " + count +
                     " are inside their bands: the model is consistent with the record";
    return;
  }
  const std::string why = "the model or its parameters are wrong";
  result.verdict = cannot + "its statistics judge it, and " + std::to_string(s.outside()) + " of " +
                   count + " are outside their bands: " + why;
  result.warnings.push_back(std::to_string(s.outside()) + " of " + count +
                            " statistics of the response are outside their bands: " + why);
}

// Every parameter's value by name, as ValidateResult::parameters holds them: the double nearest
// to the value simulated with, and the decimal given.
ParameterValues every_value(const Model& model, const ParameterValues& given) {
  const std::vector<GiNaC::numeric> values = parameter_vector(model, given);
  ParameterValues out;
  for (std::size_t p = 0; p < values.size(); ++p) {
    const std::string& name = model.parameters()[p].name;
    ParameterValue value(values[p].to_double());
    if (const auto found = given.find(name); found != given.end()) {
      value.decimal = found->second.decimal;
    }
    out.emplace(name, std::move(value));
  }
  return out;
}

}  // namespace

ValidateResult validate(const Model& model, const DataSource& source,
                        const ValidateOptions& options) {
  const AlgebraLock lock;
  options.validate();
  for (const std::string& name : options.center) {
    if (model.variable_index(name) < 0) {
      throw UsageError("center", "'" + name + "' is not a state or input of model " + model.name());
    }
  }
  options.replay.record.validate(&model);
  const std::size_t parameters = model.parameters().size();
  const bool square = std::all_of(options.covariance.begin(), options.covariance.end(),
                                  [&](const auto& row) { return row.size() == parameters; });
  if (!options.covariance.empty() && (options.covariance.size() != parameters || !square)) {
    throw UsageError("covariance", "expected " + std::to_string(parameters) + " rows of " +
                                       std::to_string(parameters) +
                                       " entries, one per parameter of model " + model.name());
  }
  ValidateResult result;
  result.model = std::make_shared<const Model>(model);
  result.parameters = every_value(model, options.replay.parameters);
  Record record = read_record(model, source, options.replay);
  result.centered = center_record(model, record, options.center);
  result.replay = replay_record(*result.model, std::move(record), options.replay);
  const Replay& replay = result.replay;
  const std::vector<std::size_t> outputs = measured_outputs(model, replay.record);
  if (replay.record.missing.rows > 0) {
    result.warnings.push_back(missing_warning(replay.record.missing));
  }
  if (replay.substep_change >= ReplayOptions::kSubstepTolerance) {
    result.warnings.push_back(substep_warning(replay));
  }
  const RecordSimulator simulator(model, options.replay.parameters, replay.interpolation,
                                  replay.record.dt, replay.substeps);
  result.sensitivity = measure_sensitivity(model, simulator, replay);
  choose_skips(model, simulator, options, result);
  // A trajectory that cannot be reproduced says nothing against the model.
  std::vector<ComparedRows> rows;
  for (std::size_t j : outputs) rows.push_back(compared_rows(model, replay, j, result.skip));
  NoiseBand& band = result.noise_band;
  if (result.sensitivity.sensitive) {
    band.not_compared = "the trajectory cannot be reproduced: the statistics judge the model";
  } else {
    band = compare_noise_band(model, result.parameters, options.covariance, replay, result.skip,
                              outputs, rows);
  }
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    OutputFit fit = output_fit(model, outputs[o], rows[o]);
    add_correlation_checks(model, replay.record, result.skip, std::move(rows[o].error),
                           options.lags, fit);
    const bool inside = band.compared && band.outputs[o].inside();
    if (!result.sensitivity.sensitive && add_fit_warnings(fit, inside, result.warnings)) {
      result.consistent = false;
    }
    result.outputs.push_back(std::move(fit));
  }
  add_band_warnings(band, result);
  // The statistics judge a sensitive model, and show where a reproducible trajectory that
  // fails differs: over every output the record has, states and measured derivatives.
  if (result.sensitivity.sensitive || !result.consistent) {
    result.statistics = compare_statistics(model, simulator, replay, outputs);
  }
  judge(result);
  return result;
}

}  // namespace momentid
