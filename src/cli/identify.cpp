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
  std::string plot;
};

int run_identify(IdentifyCommand& command) {
  IdentifyArguments& a = command.arguments;
  IdentifyOptions& options = a.options.identify;
  const IdentifyInputs inputs = read_identify_arguments(a, "identify MODEL DATA...");
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
  CLI::App* sub = app.add_subcommand(
      "identify", "estimate the parameters of a model from data, with standard errors");
  add_identify_arguments(sub, command->arguments, "identify");
  sub->add_option("--plot", command->plot,
                  "draw the restoring force and the backbone with their 95% bands into this SVG "
                  "file (an oscillator with one nonlinear stiffness)")
      ->type_name("FILE.svg");
  return {sub, [command] { return run_identify(*command); }};
}

}  // namespace momentid::cli
