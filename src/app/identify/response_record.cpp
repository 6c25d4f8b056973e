#include "app/identify/response_record.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <tuple>
#include <utility>

#include "app/identify/moment_lists.hpp"
#include "app/validate/record.hpp"
#include "app/validate/replay.hpp"

namespace momentid {
namespace {

// The misfit belongs to the response at the record's amplitudes: a response whose channels' spread
// is not within this factor of the record's (less its noise) is not the record's.
constexpr double kResponseSpread = 1.5;

// The state or derivative channel of the response `clean` that spreads furthest from the
// record's (its standard deviation against the record's less its noise), and by what factor,
// where one lies beyond kResponseSpread either way: a wrong model's response, damped, stiffened
// or running away from the record, holds another misfit than the record's equations.
std::optional<std::pair<std::string, double>> stray_channel(const IdentifyResult& result,
                                                            const DataMoments& clean,
                                                            std::size_t states,
                                                            std::size_t inputs) {
  std::optional<std::pair<std::string, double>> out;
  for (std::size_t c = 0; c < clean.channels.size() && c < result.data.channels.size(); ++c) {
    const ChannelStatistics& record = result.data.channels[c];
    if (c >= states && c < states + inputs) continue;
    const double noise = c < result.lagged->noise.size() ? result.lagged->noise[c] : 0.0;
    const double ratio = std::sqrt(clean.channels[c].variance /
                                   std::max(record.variance - noise, 0.01 * record.variance));
    const double off = std::abs(std::log(ratio));
    if ((off > std::log(kResponseSpread) || !std::isfinite(off)) &&
        (!out || !(off <= std::abs(std::log(out->second))))) {
      out = {record.name, ratio};
    }
  }
  return out;
}

// The misfit is read off the first million rows of the response: beyond, its average would
// change little, and the response's record is held in memory.
constexpr std::size_t kMisfitRows = std::size_t{1} << 20;

}  // namespace

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

std::vector<double> response_residual(const IdentifyResult& result, const LaggedRows& rows,
                                      const DataSource& source, const IdentifyOptions& options,
                                      DataOptions data_options,
                                      const std::vector<std::string>& states,
                                      const std::vector<std::string>& inputs,
                                      IdentifyResult::Integration::Misfit& misfit) {
  const ResponseRecord response(result, source, options, kMisfitRows);
  // The response's columns are named after the model's variables, and it carries no offset.
  RecordOptions record;
  record.dt = result.data.time_step;
  record.hold = options.record.hold;
  record.control = options.record.control;
  for (const auto& formed : result.integration->formed) {
    record.columns[formed.state] = formed.variable;
  }
  data_options.record = std::move(record);
  data_options.offsets.clear();
  const DataMoments clean =
      moments_from_data(response.source(), states, inputs, result.lagged->moments, data_options);
  misfit.rows = clean.rows;
  if (const auto stray = stray_channel(result, clean, states.size(), inputs.size())) {
    std::tie(misfit.channel, misfit.spread) = *stray;
    misfit.failure = "the identified model's response does not follow the record";
    return {};
  }
  const std::map<Moment, std::size_t> index = moment_index(result.lagged->moments);
  const auto value = [&](const MomentRows::Entry& entry) {
    double sum = entry.constant;
    for (const auto& [k, weight] : entry.moments) {
      sum += weight * clean.estimates.mean[index.at(rows.moments[k])];
    }
    return sum;
  };
  std::vector<double> theta;
  for (const ParameterEstimate& p : result.parameters()) theta.push_back(p.estimate);
  std::vector<double> out;
  for (std::size_t r = 0; r < rows.rows.b.size(); ++r) {
    double g = -value(rows.rows.b[r]);
    for (std::size_t p = 0; p < theta.size(); ++p) g += theta[p] * value(rows.rows.a[r][p]);
    out.push_back(g);
  }
  return out;
}

}  // namespace momentid
