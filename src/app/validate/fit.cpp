#include "app/validate/fit.hpp"

#include <algorithm>
#include <cmath>

#include "app/validate/record.hpp"
#include "momentid/error.hpp"

namespace momentid {
namespace {

// The number of rows in the first 10% of each run's compared rows (at least one).
std::size_t start_rows(std::size_t compared) {
  return std::max<std::size_t>(1, (compared + 9) / 10);
}

}  // namespace

std::size_t output_variable(const Model& model, std::size_t j) {
  const std::size_t states = model.states().size();
  return j < states ? j : j + model.inputs().size();
}

std::vector<std::size_t> measured_outputs(const Model& model, const Record& record) {
  std::vector<std::size_t> out;
  const std::size_t outputs = model.states().size() + model.measured_derivatives().size();
  for (std::size_t j = 0; j < outputs; ++j) {
    if (record.column_of(output_variable(model, j)) >= 0) out.push_back(j);
  }
  if (out.empty()) {
    throw DataError(
        file_start(record.name),
        "none of the states of model " + model.name() +
            (model.measured_derivatives().empty() ? "" : ", nor of its measured columns,") +
            " is a column of the data: there is nothing to compare");
  }
  return out;
}

const std::vector<double>& simulated_output(const Model& model, const Replay& replay, std::size_t r,
                                            std::size_t j) {
  const std::size_t states = model.states().size();
  return j < states ? replay.simulated[r][j] : replay.derivatives[r][j - states];
}

ComparedRows compared_rows(const Model& model, const Replay& replay, std::size_t output,
                           const std::vector<std::size_t>& skip) {
  const Record& record = replay.record;
  const auto column = static_cast<std::size_t>(record.column_of(output_variable(model, output)));
  ComparedRows out;
  out.error.resize(record.runs.size());
  out.measured.resize(record.runs.size());
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const std::vector<double>& y = record.runs[r].columns[column];
    const std::vector<double>& sim = simulated_output(model, replay, r, output);
    for (std::size_t n = skip[r]; n < y.size(); ++n) {
      out.measured[r].push_back(y[n]);
      out.error[r].push_back(y[n] - sim[n]);
    }
  }
  return out;
}

OutputFit output_fit(const Model& model, std::size_t output, const ComparedRows& rows) {
  OutputFit fit;
  fit.name = model.variables()[output_variable(model, output)].name;
  fit.state = output;
  double sum_y = 0;
  for (std::size_t r = 0; r < rows.error.size(); ++r) {
    for (double y : rows.measured[r]) sum_y += y;
    fit.samples += rows.error[r].size();
  }
  const double count = static_cast<double>(fit.samples);
  const double mean_y = sum_y / count;
  double ee = 0, yy = 0, start_ee = 0, rest_ee = 0;
  std::size_t start_count = 0;
  for (std::size_t r = 0; r < rows.error.size(); ++r) {
    const std::vector<double>& error = rows.error[r];
    const std::size_t head = start_rows(error.size());
    for (std::size_t n = 0; n < error.size(); ++n) {
      const double e2 = error[n] * error[n];
      ee += e2;
      (n < head ? start_ee : rest_ee) += e2;
      yy += (rows.measured[r][n] - mean_y) * (rows.measured[r][n] - mean_y);
    }
    start_count += std::min(head, error.size());
  }
  fit.rms = std::sqrt(ee / count);
  fit.fit = 100 * (1 - std::sqrt(ee / yy));
  fit.rms_start = std::sqrt(start_ee / static_cast<double>(start_count));
  const std::size_t rest_count = fit.samples - start_count;
  fit.rms_rest = rest_count > 0 ? std::sqrt(rest_ee / static_cast<double>(rest_count)) : NAN;
  if (!(yy > 0)) fit.fit = NAN;
  return fit;
}

bool add_fit_warnings(const OutputFit& fit, bool noise_explains,
                      std::vector<std::string>& warnings) {
  const std::size_t before = warnings.size();
  if (fit.fit < 0) {
    warnings.push_back(fit.name +
                       ": the simulation is further from the data than their mean "
                       "(fit below 0%): the model or its parameters are wrong");
  }
  if (!noise_explains && fit.rms_rest > 2 * fit.rms_start && fit.rms_start > 0) {
    warnings.push_back(fit.name +
                       ": the error grows along the record (its rms after the first 10% "
                       "is more than twice the rms over them): the simulation drifts");
  }
  return warnings.size() > before;
}

}  // namespace momentid
