// momentid select MODEL DATA [options]

#include "momentid/select.hpp"

#include <iostream>
#include <memory>

#include "cli/commands.hpp"
#include "cli/identify_arguments.hpp"
#include "cli/progress.hpp"
#include "momentid/model.hpp"
#include "momentid/writer.hpp"

namespace momentid::cli {
namespace {

struct SelectCommand {
  IdentifyArguments arguments;
  std::string output;
};

int run_select(SelectCommand& command) {
  IdentifyArguments& a = command.arguments;
  const IdentifyInputs inputs = read_identify_arguments(a, "select MODEL DATA...");
  TerminalProgress progress(!a.quiet && a.format != "json");
  a.options.identify.record.control.progress = progress.callback();
  const SelectResult result = select_terms(inputs.model, inputs.source, a.options);
  progress.finish();
  // The model file first: a report on standard output that names a file not written would mislead.
  if (!command.output.empty()) write_whole_file(command.output, chosen_model_text(result));
  write_whole_file("-", a.format == "json" ? format_json(result) : format_text(result));
  if (result.chosen.estimate.status == Status::kNothingIdentifiable) {
    std::cerr << "momentid: nothing identifiable: " << result.chosen.estimate.message << "\n";
    return kNothingIdentifiable;
  }
  return 0;
}

}  // namespace

Command add_select(CLI::App& app) {
  auto command = std::make_shared<SelectCommand>();
  CLI::App* sub =
      app.add_subcommand("select",
                         "choose the terms of a library model that the data want, with the chosen "
                         "model's estimates");
  add_identify_arguments(sub, command->arguments, "select");
  sub->add_option("-o,--output", command->output,
                  "write the chosen model as a model file, for identify, validate and simulate");
  return {sub, [command] { return run_select(*command); }};
}

}  // namespace momentid::cli
