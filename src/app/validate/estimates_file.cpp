// The parameter values of an `identify --format json` result, for validate --estimates.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/validate/record.hpp"
#include "common/json.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/validate.hpp"

namespace momentid {
namespace {

// The location of byte `offset` of `text`, the contents of file `path`, with its line for the
// caret.
SourceLocation location(const std::string& path, const std::string& text, std::size_t offset) {
  offset = std::min(offset, text.size());
  const std::size_t line_start = text.rfind('\n', offset == 0 ? 0 : offset - 1);
  const std::size_t begin = line_start == std::string::npos || offset == 0 ? 0 : line_start + 1;
  const std::size_t end = std::min(text.find('\n', begin), text.size());
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + begin, '\n'));
  return SourceLocation{path, line, static_cast<int>(offset - begin) + 1,
                        text.substr(begin, end - begin)};
}

// diagnostics.covariance: a row per parameter of as many entries, NaN for an entry that is not a
// number (the JSON writes an unknown error as null); empty without it.
std::vector<std::vector<double>> covariance_of(const nlohmann::json& document,
                                               std::size_t parameters,
                                               const SourceLocation& where) {
  if (!document.contains("diagnostics") || !document["diagnostics"].is_object() ||
      !document["diagnostics"].contains("covariance")) {
    return {};
  }
  const nlohmann::json& matrix = document["diagnostics"]["covariance"];
  const std::string shape = "\"covariance\": expected " + std::to_string(parameters) + " rows of " +
                            std::to_string(parameters) + " entries, one per parameter";
  if (!matrix.is_array() || matrix.size() != parameters) throw DataError(where, shape);
  std::vector<std::vector<double>> out;
  for (const nlohmann::json& row : matrix) {
    if (!row.is_array() || row.size() != parameters) throw DataError(where, shape);
    std::vector<double>& values = out.emplace_back();
    for (const nlohmann::json& entry : row) {
      values.push_back(entry.is_number() ? entry.get<double>() : NAN);
    }
  }
  return out;
}

}  // namespace

Estimates read_estimates(const Model& model, const std::string& path) {
  const AlgebraLock lock;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataError(file_start(path), "cannot open the estimates file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  const auto at = [&](std::size_t offset) { return location(path, text, offset); };
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
  Estimates estimates;
  ParameterValues& out = estimates.values;
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
    out[p.name] = entry["estimate"].get<double>();
  }
  for (const auto& [name, value] : parameters.items()) {
    if (model.parameter_index(name) < 0) {
      throw DataError(at(key_at(name, parameters_at)),
                      "'" + name + "' is not a parameter of model " + model.name());
    }
  }
  estimates.covariance =
      covariance_of(document, model.parameters().size(), at(key_at("covariance", 0)));
  return estimates;
}

}  // namespace momentid
