#include "momentid/validate.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "app/variables.hpp"
#include "common/decimal.hpp"
#include "common/json.hpp"
#include "momentid/data_pass.hpp"
#include "momentid/error.hpp"
#include "momentid/lagged.hpp"

namespace momentid {

int Record::column_of(std::size_t v) const {
  const auto it = std::find(variables.begin(), variables.end(), v);
  return it == variables.end() ? -1 : static_cast<int>(it - variables.begin());
}

namespace {

// z of the two-sided 99% band.
constexpr double kBand99 = 2.5758293035489004;

SourceLocation file_start(const std::string& name) { return {name, 1, 1, ""}; }

Record read_record(const Model& model, const DataSource& source, const ReplayOptions& options) {
  const std::vector<bool> present =
      variables_present(model, source, options.columns, options.layout);
  const std::size_t states = model.states().size();
  Record record;
  record.name = source.name();
  const std::vector<std::string> header = data_columns(source, options.columns, options.layout);
  record.has_time = std::find(header.begin(), header.end(), "t") != header.end();
  record.has_run = std::find(header.begin(), header.end(), "run") != header.end();
  // Every input is requested, so that one the data lack is reported as a missing column.
  std::vector<std::string> names;
  if (record.has_time) names.push_back("t");
  for (std::size_t v = 0; v < present.size(); ++v) {
    if (v >= states || present[v]) {
      record.variables.push_back(v);
      const std::string& name = model.variables()[v];
      names.push_back(name);
      const auto renamed = options.columns.find(name);
      record.columns.push_back(renamed == options.columns.end() ? name : renamed->second);
    }
  }
  const auto reader = source.open(
      {.names = names, .rename = options.columns, .min_rows = 2, .layout = options.layout});
  const std::size_t first = record.has_time ? 1 : 0;
  const std::size_t width = names.size();
  DataBlock block;
  while (reader->next(block, 65536)) {
    if (block.run_starts || record.runs.empty()) {
      record.runs.emplace_back();
      record.runs.back().number = block.run;
      record.runs.back().columns.resize(record.variables.size());
    }
    RecordRun& run = record.runs.back();
    for (std::size_t r = 0; r < block.rows; ++r) {
      const double* row = block.values.data() + r * width;
      if (record.has_time) run.time.push_back(row[0]);
      for (std::size_t c = 0; c < record.variables.size(); ++c) {
        run.columns[c].push_back(row[first + c]);
      }
    }
  }
  record.metadata = reader->metadata();
  record.missing = reader->missing();
  const std::optional<double> dt = options.dt ? options.dt : reader->time_step();
  if (!dt) {
    throw DataError(file_start(record.name),
                    "the data give no sample interval: add a t column or a '# momentid: dt=...' "
                    "line, or give --dt");
  }
  record.dt = *dt;
  return record;
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
    } else if (const VariableReading& r = readings[j]; r.base >= 0 && r.order <= 3) {
      // A polynomial of degree 3 (fewer with fewer rows) fitted to the first samples of the
      // measured variable, differentiated `order` times at the first sample.
      const std::vector<double>& base =
          run.columns[static_cast<std::size_t>(record.column_of(static_cast<std::size_t>(r.base)))];
      const std::size_t count = std::min(Replay::kStartSamples, base.size());
      const int degree = std::min<int>(3, static_cast<int>(count) - 1);
      if (r.order <= degree) {
        Eigen::MatrixXd a(count, degree + 1);
        Eigen::VectorXd b(count);
        for (std::size_t k = 0; k < count; ++k) {
          for (int p = 0; p <= degree; ++p) a(k, p) = std::pow(static_cast<double>(k), p);
          b(k) = base[k];
        }
        const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
        double factorial = 1;
        for (int p = 2; p <= r.order; ++p) factorial *= p;
        out[j] = r.scale * factorial * c(r.order) / std::pow(record.dt, r.order);
      }
      std::string derivative = model.variables()[static_cast<std::size_t>(r.base)] +
                               std::string(static_cast<std::size_t>(r.order), '\'');
      if (r.scale != 1) derivative = shortest_decimal(r.scale) + "*" + derivative;
      text = derivative + " at the start (a cubic fitted to the first " + std::to_string(count) +
             " samples of " + model.variables()[static_cast<std::size_t>(r.base)] + ")";
    } else {
      text = "0 (no column, and no kinematic equation defines it from one)";
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

// The input columns of a run, in model order.
std::vector<std::vector<double>> run_inputs(const Model& model, const Record& record,
                                            const RecordRun& run) {
  std::vector<std::vector<double>> out;
  const std::size_t states = model.states().size();
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    out.push_back(run.columns[static_cast<std::size_t>(record.column_of(states + i))]);
  }
  return out;
}

double run_start(const RecordRun& run) { return run.time.empty() ? 0.0 : run.time.front(); }

std::size_t run_label(const Record& record, std::size_t r) {
  return record.has_run ? static_cast<std::size_t>(record.runs[r].number) : r + 1;
}

// The fewest substeps (1, 2, 4, ...) for which halving the step changes the simulation of the
// first rows of the first run by less than ReplayOptions::kSubstepTolerance of each state's
// spread.
// Also returns that change, which is above the tolerance when even kMaxSubsteps do not reach it.
std::pair<int, double> chosen_substeps(const Model& model,
                                       const std::vector<GiNaC::numeric>& parameters,
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
        double mean = 0, squares = 0, change = 0;
        for (double x : a) mean += x;
        mean /= static_cast<double>(rows);
        for (std::size_t n = 0; n < rows; ++n) {
          squares += (a[n] - mean) * (a[n] - mean);
          change = std::max(change, std::abs(a[n] - b[n]));
        }
        const double spread = std::sqrt(squares / static_cast<double>(rows));
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
  if (options.dt && !(std::isfinite(*options.dt) && *options.dt > 0)) {
    throw UsageError("dt", "expected a positive number, found " + shortest_decimal(*options.dt));
  }
  Replay out;
  out.record = read_record(model, source, options);
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
    std::tie(out.substeps, out.substep_change) = chosen_substeps(model, options.parameters, out);
    out.substeps_chosen = true;
  }
  const RecordSimulator simulator(model, options.parameters, out.interpolation, record.dt,
                                  out.substeps);
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const RecordRun& run = record.runs[r];
    out.simulated.push_back(simulator.run(run_inputs(model, record, run), out.initial[r],
                                          run_start(run), run_label(record, r), run.rows()));
  }
  return out;
}

void write_replay(const Model& model, const Replay& replay, const std::string& path,
                  DataWriter::Format format) {
  const Record& record = replay.record;
  std::vector<std::string> columns;
  if (record.has_time) columns.push_back("t");
  columns.insert(columns.end(), record.columns.begin(), record.columns.end());
  if (record.has_run) columns.push_back("run");
  DataMetadata metadata;
  DataMetadata::Line line{
      {"model", model.name()},
      {"dt", shortest_decimal(record.dt)},
      {"input-hold", record.metadata.get("input-hold").value_or(to_string(InputHold::kSample))},
      {"input-file", record.name}};
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    line.emplace_back("interpolation." + model.inputs()[i].name,
                      to_string(replay.interpolation[i]));
  }
  line.emplace_back("substeps", std::to_string(replay.substeps));
  metadata.add_line(std::move(line));
  DataWriter out(path, format, metadata, columns);
  const std::size_t states = model.states().size();
  std::vector<double> row(columns.size());
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const RecordRun& run = record.runs[r];
    for (std::size_t n = 0; n < run.rows(); ++n) {
      std::size_t k = 0;
      if (record.has_time) row[k++] = run.time[n];
      for (std::size_t c = 0; c < record.variables.size(); ++c) {
        const std::size_t v = record.variables[c];
        row[k++] = v < states ? replay.simulated[r][v][n] : run.columns[c][n];
      }
      if (record.has_run) row[k] = static_cast<double>(run.number);
      out.row(row.data());
    }
  }
  out.commit();
}

std::vector<GiNaC::numeric> read_estimates(const Model& model, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataError(file_start(path), "cannot open the estimates file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  // The location of byte `offset`, with its line for the caret.
  const auto at = [&](std::size_t offset) {
    offset = std::min(offset, text.size());
    const std::size_t line_start = text.rfind('\n', offset == 0 ? 0 : offset - 1);
    const std::size_t begin = line_start == std::string::npos || offset == 0 ? 0 : line_start + 1;
    const std::size_t end = std::min(text.find('\n', begin), text.size());
    const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + begin, '\n'));
    return SourceLocation{path, line, static_cast<int>(offset - begin) + 1,
                          text.substr(begin, end - begin)};
  };
  // Where a key first appears after `from`, for messages about its value.
  const auto key_at = [&](const std::string& key, std::size_t from) {
    const std::size_t found = text.find(json_string(key), from);
    return found == std::string::npos ? from : found;
  };
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // The library's message after its own "... line L, column C: " prefix.
    std::string reason = e.what();
    const std::size_t column = reason.find("column ");
    const std::size_t colon = reason.find(": ", column == std::string::npos ? 0 : column);
    if (colon != std::string::npos) reason = reason.substr(colon + 2);
    throw DataError(at(e.byte == 0 ? 0 : e.byte - 1), "not JSON: " + reason);
  }
  const std::string expected = " (expected the output of 'momentid identify --format json')";
  if (!document.is_object() || !document.contains("parameters") ||
      !document["parameters"].is_object()) {
    throw DataError(at(0), "no \"parameters\" object" + expected);
  }
  if (document.contains("model") && document["model"].is_string() &&
      document["model"].get<std::string>() != model.name()) {
    throw DataError(at(key_at("model", 0)), "these are estimates of model '" +
                                                document["model"].get<std::string>() +
                                                "', not of '" + model.name() + "'");
  }
  const std::size_t parameters_at = key_at("parameters", 0);
  const nlohmann::json& parameters = document["parameters"];
  std::vector<GiNaC::numeric> out;
  for (const Declaration& p : model.parameters()) {
    if (!parameters.contains(p.name)) {
      throw DataError(at(parameters_at), "no estimate of parameter '" + p.name + "'" + expected);
    }
    const nlohmann::json& entry = parameters[p.name];
    const bool numeric = entry.is_object() && entry.contains("estimate") &&
                         entry["estimate"].is_number() &&
                         std::isfinite(entry["estimate"].get<double>());
    if (!numeric) {
      throw DataError(at(key_at(p.name, parameters_at)),
                      "parameter '" + p.name + "' has no finite number as its \"estimate\"");
    }
    out.emplace_back(entry["estimate"].get<double>());
  }
  for (const auto& [name, value] : parameters.items()) {
    if (model.parameter_index(name) < 0) {
      throw DataError(at(key_at(name, parameters_at)),
                      "'" + name + "' is not a parameter of model " + model.name());
    }
  }
  return out;
}

void ValidateOptions::validate() const {
  if (lags < 1 || lags > kMaxLags) {
    throw UsageError("lags", "expected a number from 1 to " + std::to_string(kMaxLags) +
                                 ", found " + std::to_string(lags));
  }
}

std::size_t CorrelationCheck::outside() const {
  return static_cast<std::size_t>(
      std::count_if(values.begin(), values.end(), [&](double v) { return std::abs(v) > band; }));
}

namespace {

// Series compared in several runs: segments of equal length in a and b.
struct Segments {
  std::vector<const double*> a, b;
  std::vector<std::size_t> length;
};

// sum over segments and t of a[t] * b[t - lag], both inside the segment.
double lagged_sum(const Segments& s, int lag) {
  double sum = 0;
  for (std::size_t k = 0; k < s.length.size(); ++k) {
    const auto n = static_cast<long>(s.length[k]);
    const long from = std::max(0L, static_cast<long>(lag));
    const long to = std::min(n, n + lag);
    if (to <= from) continue;
    sum += Eigen::Map<const Eigen::VectorXd>(s.a[k] + from, to - from)
               .dot(Eigen::Map<const Eigen::VectorXd>(s.b[k] + from - lag, to - from));
  }
  return sum;
}

// The number of rows in the first 10% of each run's compared rows (at least one).
std::size_t start_rows(std::size_t compared) {
  return std::max<std::size_t>(1, (compared + 9) / 10);
}

// The row from which the simulation of a run has forgotten its initial state (see
// ValidateResult::skip), searched over the first half of the run, and the size of the
// perturbation left at the end of the search, relative to its start.
std::pair<std::size_t, double> forgetting_row(const RecordSimulator& simulator,
                                              const std::vector<std::vector<double>>& inputs,
                                              const std::vector<double>& initial,
                                              const std::vector<std::vector<double>>& simulated,
                                              double start, std::size_t label) {
  const std::size_t n = initial.size();
  const std::size_t rows = simulated.empty() ? 0 : simulated[0].size();
  std::vector<double> spread(n, 1.0), perturbed = initial;
  for (std::size_t j = 0; j < n; ++j) {
    double mean = 0, squares = 0;
    for (double x : simulated[j]) mean += x;
    mean /= static_cast<double>(rows);
    for (double x : simulated[j]) squares += (x - mean) * (x - mean);
    const double sd = std::sqrt(squares / static_cast<double>(rows));
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

CorrelationCheck correlation(const Segments& s, int first, int last, double scale, double band,
                             const std::string& with) {
  CorrelationCheck c;
  c.with = with;
  c.first_lag = first;
  for (int lag = first; lag <= last; ++lag) c.values.push_back(lagged_sum(s, lag) / scale);
  c.band = band;
  return c;
}

}  // namespace

ValidateResult validate(const Model& model, const DataSource& source,
                        const ValidateOptions& options) {
  options.validate();
  ValidateResult result;
  result.model = std::make_shared<const Model>(model);
  result.parameters = options.replay.parameters;
  result.replay = replay(*result.model, source, options.replay);
  const Replay& replay = result.replay;
  const Record& record = replay.record;
  const std::size_t states = model.states().size();
  const auto inputs_of = [&](std::size_t r) { return run_inputs(model, record, record.runs[r]); };

  std::vector<std::size_t> outputs;
  for (std::size_t j = 0; j < states; ++j) {
    if (record.column_of(j) >= 0) outputs.push_back(j);
  }
  if (outputs.empty()) {
    throw DataError(file_start(record.name),
                    "none of the states of model " + model.name() +
                        " is a column of the data: there is nothing to compare");
  }

  if (record.missing.rows > 0) result.warnings.push_back(missing_warning(record.missing));
  if (replay.substep_change >= ReplayOptions::kSubstepTolerance) {
    char text[32];
    std::snprintf(text, sizeof text, "%.2g", replay.substep_change);
    result.warnings.push_back(
        "even " + std::to_string(replay.substeps) +
        " Runge-Kutta steps per sample change the simulation by " + text +
        " of its spread when halved: the sample interval is too coarse for the model's fastest "
        "dynamics with these values, and the simulation error is part of the fit");
  }
  result.skip_chosen = !options.skip;
  const RecordSimulator simulator(model, result.parameters, replay.interpolation, record.dt,
                                  replay.substeps);
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const std::size_t rows = record.runs[r].rows();
    std::size_t skip = 0;
    if (options.skip) {
      skip = *options.skip;
    } else if (!model.inputs().empty()) {
      const auto [row, distance] =
          forgetting_row(simulator, inputs_of(r), replay.initial[r], replay.simulated[r],
                         run_start(record.runs[r]), run_label(record, r));
      skip = row;
      if (distance > 0.01) {
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

  const int lags = options.lags;
  for (std::size_t j : outputs) {
    OutputFit fit;
    fit.name = model.states()[j].name;
    fit.state = j;
    const std::size_t column = static_cast<std::size_t>(record.column_of(j));
    // Errors and measured values over the compared rows, run by run.
    std::vector<std::vector<double>> error(record.runs.size()), measured(record.runs.size());
    double sum_y = 0, sum_e = 0;
    for (std::size_t r = 0; r < record.runs.size(); ++r) {
      const std::vector<double>& y = record.runs[r].columns[column];
      const std::vector<double>& sim = replay.simulated[r][j];
      for (std::size_t n = result.skip[r]; n < y.size(); ++n) {
        measured[r].push_back(y[n]);
        error[r].push_back(y[n] - sim[n]);
        sum_y += y[n];
        sum_e += y[n] - sim[n];
      }
      fit.samples += error[r].size();
    }
    const double count = static_cast<double>(fit.samples);
    const double mean_y = sum_y / count, mean_e = sum_e / count;
    double ee = 0, yy = 0, start_ee = 0, rest_ee = 0;
    std::size_t start_count = 0;
    for (std::size_t r = 0; r < record.runs.size(); ++r) {
      const std::size_t head = start_rows(error[r].size());
      for (std::size_t n = 0; n < error[r].size(); ++n) {
        const double e2 = error[r][n] * error[r][n];
        ee += e2;
        (n < head ? start_ee : rest_ee) += e2;
        yy += (measured[r][n] - mean_y) * (measured[r][n] - mean_y);
      }
      start_count += std::min(head, error[r].size());
    }
    fit.rms = std::sqrt(ee / count);
    fit.fit = 100 * (1 - std::sqrt(ee / yy));
    fit.rms_start = std::sqrt(start_ee / static_cast<double>(start_count));
    const std::size_t rest_count = fit.samples - start_count;
    fit.rms_rest = rest_count > 0 ? std::sqrt(rest_ee / static_cast<double>(rest_count)) : NAN;
    if (!(yy > 0)) fit.fit = NAN;

    // The correlation checks, over the error with its mean removed.
    for (auto& e : error) {
      for (double& x : e) x -= mean_e;
    }
    Segments self;
    for (std::size_t r = 0; r < record.runs.size(); ++r) {
      self.a.push_back(error[r].data());
      self.b.push_back(error[r].data());
      self.length.push_back(error[r].size());
    }
    const double e_power = lagged_sum(self, 0);
    if (e_power > 0) {
      const double white_band = kBand99 / std::sqrt(count);
      fit.autocorrelation = correlation(self, 1, lags, e_power, white_band, "");
      for (std::size_t i = 0; i < model.inputs().size(); ++i) {
        const std::size_t input_column = static_cast<std::size_t>(record.column_of(states + i));
        std::vector<std::vector<double>> u(record.runs.size());
        double sum_u = 0;
        for (std::size_t r = 0; r < record.runs.size(); ++r) {
          const std::vector<double>& x = record.runs[r].columns[input_column];
          u[r].assign(x.begin() + static_cast<long>(result.skip[r]), x.end());
          for (double v : u[r]) sum_u += v;
        }
        Segments input_self, cross;
        for (std::size_t r = 0; r < record.runs.size(); ++r) {
          for (double& v : u[r]) v -= sum_u / count;
          input_self.a.push_back(u[r].data());
          input_self.b.push_back(u[r].data());
          input_self.length.push_back(u[r].size());
          cross.a.push_back(error[r].data());
          cross.b.push_back(u[r].data());
          cross.length.push_back(u[r].size());
        }
        const double u_power = lagged_sum(input_self, 0);
        const std::string& name = model.inputs()[i].name;
        if (!(u_power > 0)) continue;
        // Bartlett: var r_eu(k) = (1/N) sum_tau rho_e(tau) rho_u(tau) for independent series.
        double bartlett = 1;
        for (int lag = 1; lag <= lags; ++lag) {
          bartlett += 2 * fit.autocorrelation->values[static_cast<std::size_t>(lag - 1)] *
                      lagged_sum(input_self, lag) / u_power;
        }
        fit.cross.push_back(correlation(cross, -lags, lags, std::sqrt(e_power * u_power),
                                        kBand99 * std::sqrt(std::max(bartlett, 0.0) / count),
                                        name));
      }
    }
    if (fit.fit < 0) {
      result.warnings.push_back(fit.name +
                                ": the simulation is further from the data than their mean "
                                "(fit below 0%): the model or its parameters are wrong");
    }
    if (fit.rms_rest > 2 * fit.rms_start && fit.rms_start > 0) {
      result.warnings.push_back(fit.name +
                                ": the error grows along the record (its rms after the first 10% "
                                "is more than twice the rms over them): the simulation drifts");
    }
    result.outputs.push_back(std::move(fit));
  }
  return result;
}

namespace {

std::string number(double x, const char* format = "%.6g") {
  if (std::isnan(x)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

std::string parameters_text(const ValidateResult& r) {
  std::string out;
  for (std::size_t p = 0; p < r.parameters.size(); ++p) {
    out += (p ? ", " : "") + r.model->parameters()[p].name + "=" +
           shortest_decimal(r.parameters[p].to_double());
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

std::string check_text(const CorrelationCheck& c) {
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
         (c.with.empty() ? "not white: the model leaves structure in the error"
                         : "the error depends on the input: the model misses part of its effect");
  return out;
}

}  // namespace

std::string format_text(const ValidateResult& r) {
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
  out += "\nskipped: " + skip_text(r, model.inputs().empty()) + "\n\n";
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
    out += "  " + f.name + ": " + check_text(*f.autocorrelation) + "\n";
    for (const CorrelationCheck& c : f.cross) out += "  " + f.name + ": " + check_text(c) + "\n";
  }
  out += "\n";
  if (r.warnings.empty()) out += "warnings: none\n";
  for (const std::string& w : r.warnings) out += "warning: " + w + "\n";
  return out;
}

namespace {

std::string json_array(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t k = 0; k < values.size(); ++k) out += (k ? ", " : "") + json_number(values[k]);
  return out + "]";
}

std::string json_check(const CorrelationCheck& c) {
  std::vector<double> lags;
  for (std::size_t k = 0; k < c.values.size(); ++k) {
    lags.push_back(c.first_lag + static_cast<int>(k));
  }
  return "{\"lags\": " + json_array(lags) + ", \"values\": " + json_array(c.values) +
         ", \"band99\": " + json_number(c.band) + ", \"outside\": " + std::to_string(c.outside()) +
         "}";
}

}  // namespace

std::string format_json(const ValidateResult& r) {
  const Replay& replay = r.replay;
  const Record& record = replay.record;
  const Model& model = *r.model;
  std::ostringstream out;
  std::size_t rows = 0;
  for (const RecordRun& run : record.runs) rows += run.rows();
  out << "{\n  \"model\": " << json_string(model.name())
      << ",\n  \"data\": " << json_string(record.name) << ",\n  \"rows\": " << rows
      << ",\n  \"runs\": " << record.runs.size() << ",\n  \"dt\": " << json_number(record.dt)
      << ",\n  \"parameters\": {";
  for (std::size_t p = 0; p < r.parameters.size(); ++p) {
    out << (p ? ", " : "") << json_string(model.parameters()[p].name) << ": "
        << json_number(r.parameters[p].to_double());
  }
  out << "},\n  \"parameters_from\": " << json_string(r.parameters_from)
      << ",\n  \"interpolation\": {";
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    out << (i ? ", " : "") << json_string(model.inputs()[i].name) << ": "
        << json_string(to_string(replay.interpolation[i]));
  }
  out << "},\n  \"substeps\": " << replay.substeps << ",\n  \"initial_state\": [";
  for (std::size_t r0 = 0; r0 < record.runs.size(); ++r0) {
    out << (r0 ? ", " : "") << "{";
    for (std::size_t j = 0; j < model.states().size(); ++j) {
      out << (j ? ", " : "") << json_string(model.states()[j].name) << ": "
          << json_number(replay.initial[r0][j]);
    }
    out << "}";
  }
  out << "],\n  \"initial_how\": {";
  for (std::size_t j = 0; j < model.states().size(); ++j) {
    out << (j ? ", " : "") << json_string(model.states()[j].name) << ": "
        << json_string(replay.initial_how[j]);
  }
  out << "},\n  \"skip\": [";
  for (std::size_t k = 0; k < r.skip.size(); ++k) out << (k ? ", " : "") << r.skip[k];
  out << "],\n  \"skip_chosen\": " << (r.skip_chosen ? "true" : "false") << ",\n  \"outputs\": {";
  for (std::size_t k = 0; k < r.outputs.size(); ++k) {
    const OutputFit& f = r.outputs[k];
    out << (k ? "," : "") << "\n    " << json_string(f.name) << ": {\"samples\": " << f.samples
        << ", \"rms\": " << json_number(f.rms) << ", \"fit_percent\": " << json_number(f.fit)
        << ", \"rms_first_10pct\": " << json_number(f.rms_start)
        << ", \"rms_rest\": " << json_number(f.rms_rest) << ",\n      \"autocorrelation\": "
        << (f.autocorrelation ? json_check(*f.autocorrelation) : "null")
        << ",\n      \"cross_correlation\": {";
    for (std::size_t c = 0; c < f.cross.size(); ++c) {
      out << (c ? ", " : "") << json_string(f.cross[c].with) << ": " << json_check(f.cross[c]);
    }
    out << "}}";
  }
  out << "\n  },\n  \"warnings\": " << json_strings(r.warnings) << "\n}\n";
  return out.str();
}

}  // namespace momentid
