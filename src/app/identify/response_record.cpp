#include "app/identify/response_record.hpp"

#include "app/validate/record.hpp"
#include "app/validate/replay.hpp"

namespace momentid {

ReplayOptions replay_at_estimates(const IdentifyResult& result, const IdentifyOptions& options) {
  ReplayOptions out;
  out.record = options.record;
  for (const ParameterEstimate& p : result.parameters()) out.parameters[p.name] = p.estimate;
  return out;
}

ResponseRecord::ResponseRecord(const IdentifyResult& result, const DataSource& source,
                               const IdentifyOptions& options, std::size_t most_rows) {
  const Model& model = *result.model;
  const ReplayOptions replay_options = replay_at_estimates(result, options);
  Record record = read_record(model, source, replay_options, most_rows);
  remove_means(model, record, result.centered);
  const Replay replay = replay_record(model, std::move(record), replay_options);
  const Record& read = replay.record;
  std::vector<std::string> names;
  if (read.has_time) {
    names.emplace_back("t");
    columns_.push_back(series_times(read));
  }
  if (read.runs.size() > 1) {
    names.emplace_back("run");
    columns_.push_back(series_runs(read));
  }
  for (std::size_t c = 0; c < read.variables.size(); ++c) {
    const Variable& variable = model.variables()[read.variables[c]];
    const auto index = static_cast<std::size_t>(variable.index);
    std::vector<double> values;
    for (std::size_t r = 0; r < read.runs.size(); ++r) {
      const std::vector<double>& run =
          variable.kind == VariableKind::kState        ? replay.simulated[r][index]
          : variable.kind == VariableKind::kDerivative ? replay.derivatives[r][index]
                                                       : read.runs[r].columns[c];
      values.insert(values.end(), run.begin(), run.end());
    }
    names.push_back(variable.name);
    columns_.push_back(std::move(values));
  }
  for (std::size_t c = 0; c < columns_.size(); ++c) {
    data_.columns.push_back({.name = names[c], .values = columns_[c].data(), .stride = 1});
  }
  data_.rows = columns_.empty() ? 0 : columns_.front().size();
  data_.metadata = read.metadata;
  data_.name = "the response of the identified model to the inputs of " + source.name();
}

DataSource ResponseRecord::source() const { return DataSource::memory(data_); }

}  // namespace momentid
