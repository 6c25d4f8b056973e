#pragma once
// The options identify and select share: the record, the lagged equations, the noise, the
// parameters fixed and the channels centered; each command adds its own.

#include <optional>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "momentid/identify.hpp"

namespace momentid::cli {

struct IdentifyArguments {
  std::string model;
  std::vector<std::string> data;
  bool quiet = false;
  IdentifyOptions options;
  std::string hold;
  std::string format = "text";
  std::vector<std::string> columns;
  std::optional<std::string> lags;
  std::optional<std::string> instruments;
  std::string noise = "auto";
  std::vector<std::string> center;
  std::vector<std::string> fix;
};

// MODEL, DATA and the shared options of `command`, which stores them in `arguments`. Returns
// the --lags option, which identify's zero-lag options exclude.
CLI::Option* add_identify_arguments(CLI::App* command, IdentifyArguments& arguments);

// The model and the data the arguments name, with arguments.options completed from the text
// of the options. `usage` names the command's form in messages ("identify MODEL DATA...").
struct IdentifyInputs {
  Model model;
  DataSource source;
};
IdentifyInputs read_identify_arguments(IdentifyArguments& arguments, const std::string& usage);

}  // namespace momentid::cli
