#include "momentid/record_options.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <regex>
#include <span>

#include "common/decimal.hpp"
#include "momentid/error.hpp"
#include "momentid/model.hpp"

namespace momentid {

void RecordOptions::validate(const Model* model) const {
  if (dt && !(std::isfinite(*dt) && *dt > 0)) {
    throw UsageError("dt", "expected a positive number");
  }
  if (dt && (*dt < kMinInterval || *dt > kMaxInterval)) {
    throw UsageError("dt", "expected a sample interval from " + shortest_decimal(kMinInterval) +
                               " to " + shortest_decimal(kMaxInterval) + ", found " +
                               shortest_decimal(*dt));
  }
  if (model == nullptr) return;
  const std::vector<std::string> variables = model->channel_names();
  for (const auto& column : columns) {
    if (column.first == "t") continue;
    if (std::find(variables.begin(), variables.end(), column.first) == variables.end()) {
      throw UsageError("columns",
                       "'" + column.first + "' is not a state or input of model " + model->name());
    }
  }
}

void RecordOptions::check_record_interval(double dt, const SourceLocation& where) {
  if (dt >= kMinInterval && dt <= kMaxInterval) return;
  throw DataError(where, "the sample interval " + shortest_decimal(dt) +
                             " (the record's own: its time column, metadata or stored interval) "
                             "is outside " +
                             shortest_decimal(kMinInterval) + " to " +
                             shortest_decimal(kMaxInterval) +
                             ": give the times in other units, or the interval with " +
                             UsageError::mention("dt"));
}

namespace {

bool name_free(const Model& model, const std::string& name) {
  const auto& constants = model.constants();
  return model.variable_index(name) < 0 && model.parameter_index(name) < 0 &&
         std::none_of(constants.begin(), constants.end(),
                      [&](const Declaration& c) { return c.name == name; });
}

// The state whose first derivative `written` (v' or y'' through y' = v) is, or -1 when the
// model file's own statement should say why not.
int derivative_state(const Model& model, const std::string& written, const std::string& item) {
  const std::size_t primes = written.size() - written.find_last_not_of('\'') - 1;
  const std::string base = written.substr(0, written.size() - primes);
  const int state = model.variable_index(base);
  if (state < 0 ||
      model.variables()[static_cast<std::size_t>(state)].kind != VariableKind::kState) {
    throw UsageError("columns", item + ": " + base + " is not a state of model " + model.name() +
                                    " (a column may hold a state's derivative)");
  }
  if (primes == 1) return state;
  const std::optional<Kinematic> k = primes == 2 ? model.kinematic(state) : std::nullopt;
  return k && k->ratio == 1 ? k->state : -1;
}

// `model` with `measured name = written` added, or nullopt when `name` cannot be a name there.
std::optional<Model> with_measured(const Model& model, const std::string& name,
                                   const std::string& key, const std::string& item) {
  const std::string statement = "measured " + name + " = " + key;
  const std::string text = model.text() + "\n" + statement + "\n";
  const auto line = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  try {
    return parse_model(text, model.file());
  } catch (const ParseError& e) {
    if (e.location().line == line) return std::nullopt;  // a reserved word
    throw;
  } catch (const ModelError& e) {
    if (e.location().line != line) throw;
    throw UsageError("columns", item + ": " + e.message());
  }
}

}  // namespace

Model declare_derivative_columns(const Model& model, RecordOptions& record,
                                 const DataSource& source) {
  const DataMetadata metadata =
      source.open({.names = {}, .rename = record.columns, .min_rows = 0, .layout = record.layout})
          ->metadata();
  std::vector<int> given;  // the states whose derivative has a column already
  for (const MeasuredDerivative& d : model.measured_derivatives()) given.push_back(d.state);
  for (const auto& [key, column] : record.columns) {
    if (key.find('\'') != std::string::npos) {
      given.push_back(derivative_state(model, key, key + "=" + column));
    }
  }
  for (const DataMetadata::Line& line : metadata.lines()) {
    for (const auto& [key, written] : line) {
      if (!key.starts_with("measured.")) continue;
      // A declaration that does not fit this model (the record made by another) is left alone.
      const std::string column = key.substr(std::string("measured.").size());
      const std::string base = written.substr(0, written.find('\''));
      const int v = model.variable_index(base);
      if (v < 0 || model.variables()[static_cast<std::size_t>(v)].kind != VariableKind::kState ||
          written.size() - base.size() > 2) {
        continue;
      }
      const int state = derivative_state(model, written, written);
      if (state < 0 || model.kinematic(state) ||
          std::find(given.begin(), given.end(), state) != given.end()) {
        continue;
      }
      record.columns.emplace(written, column);
      given.push_back(state);
    }
  }
  return declare_derivative_columns(model, record);
}

Model declare_derivative_columns(const Model& model, RecordOptions& record) {
  Model out = model;
  std::map<std::string, std::string> columns;
  for (const auto& [key, column] : record.columns) {
    if (key.find('\'') == std::string::npos) {
      columns.emplace(key, column);
      continue;
    }
    const std::string item = key + "=" + column;
    const int state = derivative_state(out, key, item);
    const int declared = state >= 0 ? out.measured_derivative_of(state) : -1;
    std::string name =
        declared >= 0 ? out.variables()[static_cast<std::size_t>(declared)].name : "";
    // A new column variable: the column's name when it can be one, else the state's with _dot.
    std::vector<std::string> candidates;
    static const std::regex identifier("[A-Za-z_][A-Za-z0-9_]*");
    if (std::regex_match(column, identifier)) candidates.push_back(column);
    const std::string stem = (state >= 0 ? out.states()[static_cast<std::size_t>(state)].name
                                         : key.substr(0, key.find('\''))) +
                             "_dot";
    for (int n = 1; n <= 9; ++n) candidates.push_back(stem + (n > 1 ? std::to_string(n) : ""));
    for (std::size_t i = 0; name.empty() && i < candidates.size(); ++i) {
      if (!name_free(out, candidates[i])) continue;
      if (std::optional<Model> extended = with_measured(out, candidates[i], key, item)) {
        out = std::move(*extended);
        name = candidates[i];
      }
    }
    if (name.empty() || !columns.emplace(name, column).second) {
      throw UsageError("columns", item + " and " + name + "=" + columns[name] +
                                      " name the same channel, " + name);
    }
  }
  record.columns = std::move(columns);
  return out;
}

}  // namespace momentid
