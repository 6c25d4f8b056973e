// momentid convert IN OUT [--format csv|bin|npy|mat|mat73|h5]

#include "momentid/convert.hpp"

#include <cmath>
#include <iostream>
#include <memory>

#include "cli/commands.hpp"

namespace momentid::cli {
namespace {

struct ConvertCommand {
  std::string input, output, format;
  FileLayout layout;
  std::optional<double> dt;
};

int run_convert(const ConvertCommand& command) {
  const std::optional<FileFormat> format = command.format.empty()
                                               ? format_for_path(command.output)
                                               : parse_file_format(command.format, "format");
  if (!format) {
    throw UsageError("cannot tell the format of '" + command.output +
                     "' from its name (.csv, .bin, .npy, .mat, .h5): give --format");
  }
  if (command.dt && !(std::isfinite(*command.dt) && *command.dt > 0)) {
    throw UsageError("--dt: expected a positive number");
  }
  for (const std::string& note :
       convert(data_source(command.input), command.output, *format, command.layout, command.dt)) {
    std::cerr << "momentid: note: " << note << "\n";
  }
  return 0;
}

}  // namespace

Command add_convert(CLI::App& app) {
  auto command = std::make_shared<ConvertCommand>();
  CLI::App* sub =
      app.add_subcommand("convert", "copy a data file into another format, with its metadata");
  sub->add_option("IN", command->input,
                  "data file in any format momentid reads, - for standard input")
      ->required();
  sub->add_option("OUT", command->output, "the file to write")->required();
  sub->add_option("--format", command->format,
                  "csv, bin, npy, mat (level 5), mat73 (level 7.3) or h5; default: by OUT's name")
      ->check(CLI::IsMember(names_of<FileFormat>()));
  sub->add_option("--dt", command->dt, "the sample interval, stored in OUT's metadata");
  add_layout_options(sub, command->layout);
  add_stdin_limit(sub);
  return {sub, [command] { return run_convert(*command); }};
}

}  // namespace momentid::cli
