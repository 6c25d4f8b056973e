// momentid validate MODEL DATA [--set p=v,... | --estimates FILE.json] [options]

#include "momentid/validate.hpp"

#include <charconv>
#include <cmath>
#include <memory>

#include "cli/commands.hpp"
#include "momentid/model.hpp"
#include "momentid/writer.hpp"

namespace momentid::cli {
namespace {

struct ValidateCommand {
  std::string model;
  std::string data;
  std::vector<std::string> set;
  std::string estimates;
  ReplayArguments replay;
  std::optional<std::size_t> skip;
  std::string format = "text";
  std::string plot;
  std::string window;
  ValidateOptions options;
};

// `FROM:TO`, two times.
std::pair<double, double> window_option(const std::string& text) {
  const std::size_t colon = text.find(':');
  std::pair<double, double> out{0, 0};
  const auto parse = [&](std::string_view part, double& into) {
    const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), into);
    return error == std::errc() && end == part.data() + part.size() && std::isfinite(into);
  };
  if (colon == std::string::npos || !parse(std::string_view(text).substr(0, colon), out.first) ||
      !parse(std::string_view(text).substr(colon + 1), out.second) || !(out.second > out.first)) {
    throw UsageError("--window: expected FROM:TO, two times with FROM < TO, found '" + text + "'");
  }
  return out;
}

int run_validate(ValidateCommand& command) {
  ReplayOptions& replay = command.options.replay;
  read_replay_columns(command.replay, replay);
  const Model file = model_argument(command.model, command.data, "validate MODEL DATA");
  // Once: a pipe or standard input is read whole into a file of its own.
  const DataSource source = data_source(command.data);
  const Model model = declare_derivative_columns(file, replay.record, source);
  std::string from = "the model's nominal values";
  if (!command.estimates.empty()) {
    from = command.estimates + (command.set.empty() ? "" : ", then --set");
    Estimates estimates = read_estimates(model, command.estimates);
    replay.parameters = std::move(estimates.values);
    command.options.covariance = std::move(estimates.covariance);
  } else if (!command.set.empty()) {
    from += " and --set";
  }
  for (auto& [name, value] : parse_parameter_values(model, command.set)) {
    replay.parameters.insert_or_assign(name, value);
    // A value set is exact: the estimates' errors do not widen the noise band for it.
    if (!command.options.covariance.empty()) {
      const auto p = static_cast<std::size_t>(model.parameter_index(name));
      for (std::size_t q = 0; q < command.options.covariance.size(); ++q) {
        command.options.covariance[p][q] = command.options.covariance[q][p] = 0;
      }
    }
  }
  command.options.center = read_replay_arguments(command.replay, model, replay);
  command.options.skip = command.skip;
  std::optional<std::pair<double, double>> window;
  if (!command.window.empty()) window = window_option(command.window);
  ValidateResult result = validate(model, source, command.options);
  result.parameters_from = from;
  if (!command.plot.empty()) write_plot(result, command.plot, window);
  write_whole_file("-", command.format == "json" ? format_json(result) : format_text(result));
  return 0;
}

}  // namespace

Command add_validate(CLI::App& app) {
  auto command = std::make_shared<ValidateCommand>();
  CLI::App* sub = app.add_subcommand(
      "validate",
      "simulate a model through a record's inputs and compare it with the record's states");
  sub->add_option("MODEL", command->model, "model file")->required();
  sub->add_option("DATA", command->data, "data file (CSV or binary), - for standard input")
      ->required();
  sub->add_option("--set", command->set,
                  "parameter values NAME=VALUE, overriding the model's nominal values and "
                  "--estimates")
      ->delimiter(',');
  sub->add_option("--estimates", command->estimates,
                  "the parameter values of an 'identify --format json' result");
  sub->add_option("--skip", command->skip,
                  "rows left out at the start of each run (default: until the model has "
                  "forgotten its initial state)");
  sub->add_option("--lags", command->options.lags, "lags of the correlation checks (default 25)")
      ->check(CLI::Range(1, ValidateOptions::kMaxLags));
  sub->add_option("--format", command->format, "output format")
      ->check(CLI::IsMember({"text", "json"}));
  auto* plot = sub->add_option("--plot", command->plot, "draw the comparison into this SVG file");
  sub->add_option("--window", command->window,
                  "FROM:TO, the times the plot shows (default: the first 2000 compared rows)")
      ->needs(plot);
  add_replay_arguments(sub, command->replay, command->options.replay);
  return {sub, [command] { return run_validate(*command); }};
}

}  // namespace momentid::cli
