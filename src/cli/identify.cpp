// momentid identify MODEL DATA [options]

#include "momentid/identify.hpp"

#include <iostream>
#include <memory>

#include "cli/commands.hpp"
#include "cli/identify_arguments.hpp"
#include "cli/progress.hpp"
#include "momentid/model.hpp"
#include "momentid/writer.hpp"

namespace momentid::cli {
namespace {

struct IdentifyCommand {
  IdentifyArguments arguments;
  std::optional<std::string> multipliers;
  std::string weighting = to_string(Weighting::kAuto);
  std::string method = to_string(Method::kAuto);
  std::string extrapolate;
  std::string plot;
};

int run_identify(IdentifyCommand& command) {
  IdentifyArguments& a = command.arguments;
  IdentifyOptions& options = a.options;
  const IdentifyInputs inputs = read_identify_arguments(a, "identify MODEL DATA...");
  if (command.multipliers) {
    options.multipliers =
        parse_multiplier_list(inputs.model, *command.multipliers, "--multipliers");
  }
  options.weighting = parse_weighting(command.weighting, "weighting");
  options.method = parse_method(command.method, "method");
  options.extrapolate = command.extrapolate == "dt";
  TerminalProgress progress(!a.quiet && a.format != "json");
  options.record.control.progress = progress.callback();
  const IdentifyResult result = identify(inputs.model, inputs.source, options);
  progress.finish();
  if (!command.plot.empty()) write_engineering_plot(result, command.plot);
  write_whole_file("-", a.format == "json" ? format_json(result) : format_text(result));
  if (result.estimate.status == Status::kNothingIdentifiable) {
    std::cerr << "momentid: nothing identifiable: " << result.estimate.message << "\n";
    return kNothingIdentifiable;
  }
  return 0;
}

}  // namespace

Command add_identify(CLI::App& app) {
  auto command = std::make_shared<IdentifyCommand>();
  IdentifyOptions& options = command->arguments.options;
  CLI::App* sub = app.add_subcommand(
      "identify", "estimate the parameters of a model from data, with standard errors");
  CLI::Option* lags = add_identify_arguments(sub, command->arguments);
  auto* multipliers =
      sub->add_option("--multipliers", command->multipliers, "multipliers, as for derive");
  lags->excludes(multipliers);
  sub->add_option("--degree", options.degree, "multipliers up to this degree")
      ->check(CLI::Range(1, IdentifyOptions::kMaxDegree))
      ->excludes(multipliers);
  sub->add_option("--method", command->method,
                  "zero-lag, lagged, or auto: lagged for measured records (unbiased under white "
                  "sensor noise), zero-lag for records simulated without noise")
      ->check(CLI::IsMember(names_of<Method>()));
  sub->add_option("--weighting", command->weighting,
                  "ls (least squares), gmm (two-step optimal, with the J test), or auto: gmm "
                  "when the equations outnumber the parameters")
      ->check(CLI::IsMember(names_of<Weighting>()));
  sub->add_option("--extrapolate", command->extrapolate,
                  "dt: estimate the bias of sampling from every other sample, and remove it when "
                  "it exceeds its error (zero-lag equations, inputs sampled, not held)")
      ->check(CLI::IsMember({"dt"}));
  sub->add_option("--plot", command->plot,
                  "draw the restoring force and the backbone with their 95% bands into this SVG "
                  "file (an oscillator with one nonlinear stiffness)");
  return {sub, [command] { return run_identify(*command); }};
}

}  // namespace momentid::cli
