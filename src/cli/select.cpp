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
  SelectOptions options;
  std::string output;
  std::string validation;
};

int run_select(SelectCommand& command) {
  IdentifyArguments& a = command.arguments;
  const IdentifyInputs inputs = read_identify_arguments(a, "select MODEL DATA...");
  TerminalProgress progress(!a.quiet && a.format != "json");
  a.options.record.control.progress = progress.callback();
  command.options.identify = a.options;
  if (!command.validation.empty())
    command.options.validation = DataSource::file(command.validation);
  const SelectResult result = select_terms(inputs.model, inputs.source, command.options);
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
  add_identify_arguments(sub, command->arguments);
  sub->add_option("-o,--output", command->output,
                  "write the chosen model as a model file, for identify, validate and simulate");
  sub->add_option("--exhaustive", command->options.exhaustive,
                  "score every subset up to this many candidates, else eliminate backward "
                  "(default 16)")
      ->check(CLI::Range(std::size_t{0}, SelectOptions::kMaxExhaustive));
  sub->add_option("--ranked", command->options.ranked, "the subsets the ranking shows (default 5)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{100}));
  sub->add_option("--validate", command->validation,
                  "a second record: the best three subsets, each identified on DATA, simulated "
                  "through its inputs and compared with it");
  return {sub, [command] { return run_select(*command); }};
}

}  // namespace momentid::cli
