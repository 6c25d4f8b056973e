#include "app/validate/record.hpp"

#include <algorithm>

#include "app/variables.hpp"
#include "common/decimal.hpp"
#include "momentid/algebra_lock.hpp"

namespace momentid {

int Record::column_of(std::size_t v) const {
  const auto it = std::find(variables.begin(), variables.end(), v);
  return it == variables.end() ? -1 : static_cast<int>(it - variables.begin());
}

namespace {

// value_at(run, row) for every run's rows, one run after the other.
template <class ValueAt>
std::vector<double> concatenated(const Record& record, ValueAt value_at) {
  std::vector<double> out;
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    for (std::size_t n = 0; n < record.runs[r].rows(); ++n) out.push_back(value_at(r, n));
  }
  return out;
}

}  // namespace

std::vector<double> series_times(const Record& record) {
  return concatenated(record, [&](std::size_t r, std::size_t n) {
    const RecordRun& run = record.runs[r];
    return run.time.empty() ? static_cast<double>(n) * record.dt : run.time[n];
  });
}

std::vector<double> series_runs(const Record& record) {
  return concatenated(record, [&](std::size_t r, std::size_t) {
    return static_cast<double>(record.has_run ? record.runs[r].number : static_cast<long>(r) + 1);
  });
}

std::vector<double> series_recorded(const Record& record, std::size_t v) {
  const auto c = static_cast<std::size_t>(record.column_of(v));
  return concatenated(record,
                      [&](std::size_t r, std::size_t n) { return record.runs[r].columns[c][n]; });
}

std::vector<double> series_simulated(const Replay& replay, std::size_t j) {
  return concatenated(replay.record,
                      [&](std::size_t r, std::size_t n) { return replay.simulated[r][j][n]; });
}

SourceLocation file_start(const std::string& name) { return {name, 1, 1, ""}; }

Record read_record(const Model& model, const DataSource& source, const ReplayOptions& options,
                   std::size_t most_rows) {
  const std::vector<bool> present = variables_present(model, source, options.record);
  Record record;
  record.name = source.name();
  const std::vector<std::string> header = data_columns(source, options.record);
  record.has_time = std::find(header.begin(), header.end(), "t") != header.end();
  record.has_run = std::find(header.begin(), header.end(), "run") != header.end();
  // Every input is requested, so that one the data lack is reported as a missing column.
  std::vector<std::string> names;
  if (record.has_time) names.push_back("t");
  for (std::size_t v = 0; v < present.size(); ++v) {
    if (model.variables()[v].kind == VariableKind::kInput || present[v]) {
      record.variables.push_back(v);
      const std::string& name = model.variables()[v].name;
      names.push_back(name);
      const auto renamed = options.record.columns.find(name);
      record.columns.push_back(renamed == options.record.columns.end() ? name : renamed->second);
    }
  }
  const auto reader = source.open({.names = names,
                                   .rename = options.record.columns,
                                   .min_rows = 2,
                                   .layout = options.record.layout});
  const std::size_t first = record.has_time ? 1 : 0;
  const std::size_t width = names.size();
  DataBlock block;
  // A file that changes while it is read is said as such, also when the reader has met what a
  // cut leaves (a malformed last row).
  try {
    for (std::size_t read = 0;
         read < most_rows && reader->next(block, std::min<std::size_t>(65536, most_rows - read));
         read += block.rows) {
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
  } catch (const Error&) {
    source.check_unchanged();
    throw;
  }
  source.check_unchanged();
  record.metadata = reader->metadata();
  record.missing = reader->missing();
  const std::optional<double> dt = options.record.dt ? options.record.dt : reader->time_step();
  if (!dt) {
    throw DataError(file_start(record.name),
                    "the data give no sample interval: add a t column or a '# momentid: dt=...' "
                    "line, or give " +
                        UsageError::mention("dt"));
  }
  if (!options.record.dt) RecordOptions::check_record_interval(*dt, file_start(record.name));
  record.dt = *dt;
  return record;
}

std::map<std::string, double> center_record(const Model& model, Record& record,
                                            const std::vector<std::string>& center) {
  std::map<std::string, double> centered;
  for (std::size_t c = 0; c < record.variables.size(); ++c) {
    const std::string& name = model.variables()[record.variables[c]].name;
    if (std::find(center.begin(), center.end(), name) == center.end()) continue;
    double sum = 0;
    std::size_t count = 0;
    for (const RecordRun& run : record.runs) {
      for (double x : run.columns[c]) sum += x;
      count += run.columns[c].size();
    }
    const double mean = sum / static_cast<double>(count);
    for (RecordRun& run : record.runs) {
      for (double& x : run.columns[c]) x -= mean;
    }
    centered[name] = mean;
  }
  return centered;
}

void remove_means(const Model& model, Record& record, const std::map<std::string, double>& means) {
  for (std::size_t c = 0; c < record.variables.size(); ++c) {
    const auto mean = means.find(model.variables()[record.variables[c]].name);
    if (mean == means.end()) continue;
    for (RecordRun& run : record.runs) {
      for (double& x : run.columns[c]) x -= mean->second;
    }
  }
}

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

std::vector<std::string> write_replay(const Model& model, const Replay& replay,
                                      const std::string& path, DataWriter::Format format) {
  const AlgebraLock lock;
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
  std::size_t rows = 0;
  for (const RecordRun& run : record.runs) rows += run.rows();
  DataWriter out(path, format, metadata, columns, rows);
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
  std::vector<std::string> notes;
  if (auto note = out.note()) notes.push_back(std::move(*note));
  return notes;
}

}  // namespace momentid
