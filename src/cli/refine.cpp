// momentid refine MODEL DATA [--estimates FILE.json] [--set p=v,...] [--free p,...] [options]

#include "momentid/refine.hpp"

#include <cmath>
#include <memory>

#include "cli/commands.hpp"
#include "momentid/model.hpp"
#include "momentid/writer.hpp"

namespace momentid::cli {
namespace {

struct RefineCommand {
  std::string model;
  std::string data;
  std::vector<std::string> set;
  std::string estimates;
  ReplayArguments replay;
  std::string format = "text";
  RefineOptions options;
};

// The start an `identify --format json` result gives: its values, with intervals of 1.96
// standard errors from its covariance (a parameter with error 0 was fixed there).
std::vector<ParameterEstimate> start_of(const Model& model, const Estimates& estimates) {
  std::vector<ParameterEstimate> out;
  for (std::size_t p = 0; p < model.parameters().size(); ++p) {
    ParameterEstimate e;
    e.name = model.parameters()[p].name;
    e.estimate = estimates.values.at(e.name).value;
    e.std_error = estimates.covariance.empty() ? NAN : std::sqrt(estimates.covariance[p][p]);
    e.fixed = e.std_error == 0;
    e.identifiable = !std::isnan(e.std_error);
    e.ci_low = e.estimate - 1.96 * e.std_error;
    e.ci_high = e.estimate + 1.96 * e.std_error;
    out.push_back(e);
  }
  return out;
}

int run_refine(RefineCommand& command) {
  RefineOptions& options = command.options;
  ReplayOptions& replay = options.replay;
  read_replay_columns(command.replay, replay);
  const Model file = model_argument(command.model, command.data, "refine MODEL DATA");
  const DataSource source = data_source(command.data);
  const Model model = declare_derivative_columns(file, replay.record, source);
  std::string from = "the model's nominal values";
  if (!command.estimates.empty()) {
    from = command.estimates;
    options.start = start_of(model, read_estimates(model, command.estimates));
  }
  if (!command.set.empty()) from += ", then --set";
  for (const auto& given : parse_parameter_values(model, command.set)) {
    // A value set replaces the estimate's, interval and all.
    std::erase_if(options.start, [&](const ParameterEstimate& e) { return e.name == given.first; });
    replay.parameters.insert_or_assign(given.first, given.second);
  }
  options.center = read_replay_arguments(command.replay, model, replay);
  RefineResult result = refine(model, source, options);
  result.start_from = from;
  write_whole_file("-", command.format == "json" ? format_json(result) : format_text(result));
  return 0;
}

}  // namespace

Command add_refine(CLI::App& app) {
  auto command = std::make_shared<RefineCommand>();
  CLI::App* sub = app.add_subcommand(
      "refine",
      "fit a model's simulation through a record's inputs to the record's states by nonlinear "
      "least squares, from the model's values or an identify result");
  sub->add_option("MODEL", command->model, "model file")->required();
  sub->add_option("DATA", command->data, "data file (CSV or binary), - for standard input")
      ->required();
  sub->add_option("--estimates", command->estimates,
                  "start from the values of an 'identify --format json' result; its intervals "
                  "show how far the refinement moved them");
  sub->add_option("--set", command->set,
                  "start values NAME=VALUE, overriding the model's nominal values and --estimates")
      ->delimiter(',');
  sub->add_option("--free", command->options.free,
                  "the parameters refined (default: those --estimates estimated, else every "
                  "parameter not declared fixed)")
      ->delimiter(',');
  sub->add_option("--max-iterations", command->options.max_iterations,
                  "the most iterations of the search (default 50)")
      ->check(CLI::Range(1, RefineOptions::kMaxIterations));
  sub->add_option("--skip", command->options.skip,
                  "rows left out at the start of each run (default: until the simulation at the "
                  "start values has forgotten its initial state)");
  sub->add_option("--format", command->format, "output format")
      ->check(CLI::IsMember({"text", "json"}));
  add_replay_arguments(sub, command->replay, command->options.replay);
  return {sub, [command] { return run_refine(*command); }};
}

}  // namespace momentid::cli
