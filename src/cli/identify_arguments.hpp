#pragma once
// The arguments identify and select share: MODEL, DATA, the options of option_table() that the
// command takes (added by iterating the table, so that each option is described once), --format
// and -q; each command adds its own outputs (--plot, -o).

#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "cli/commands.hpp"
#include "momentid/option_table.hpp"
#include "momentid/select.hpp"

namespace momentid::cli {

struct IdentifyArguments {
  std::string model;
  std::vector<std::string> data;
  bool quiet = false;
  std::string format = "text";
  // identify's options are options.identify.
  SelectOptions options;
  // Each option of the table as CLI11 took it: its texts are read from the CLI11 option, and the
  // variables it is bound to only say what CLI11 takes (one value, or several).
  std::vector<std::pair<const OptionDescription*, CLI::Option*>> added;
  std::deque<std::string> single;
  std::deque<std::vector<std::string>> lists;
};

// MODEL, DATA, --format, -q and the options of option_table() that `command` ("identify" or
// "select") takes, which `sub` stores in `arguments`.
void add_identify_arguments(CLI::App* sub, IdentifyArguments& arguments,
                            const std::string& command);

// The model and the data the arguments name, the options given set into arguments.options by the
// table's setters (apply_options), the model completed by the columns of states' derivatives.
// `usage` names the command's form in messages ("identify MODEL DATA...").
struct IdentifyInputs {
  Model model;
  DataSource source;
};
IdentifyInputs read_identify_arguments(IdentifyArguments& arguments, const std::string& usage);

}  // namespace momentid::cli
