#include "cli/identify_arguments.hpp"

#include <algorithm>

namespace momentid::cli {
namespace {

// The option's texts, joined by commas: `--fix k=4 --fix c=1` is `--fix k=4,c=1`.
std::string text_of(const CLI::Option& option) {
  std::string out;
  for (const std::string& text : option.results()) out += (out.empty() ? "" : ",") + text;
  return out;
}

// A switch without a value name (--refine) is a flag.
bool is_flag(const OptionDescription& option) {
  return option.value == OptionValue::kSwitch && option.value_name.empty();
}

}  // namespace

IdentifyInputs read_identify_arguments(IdentifyArguments& a, const std::string& usage) {
  const Model file = model_argument(a.model, a.data.front(), usage);
  // Once: a pipe or standard input is read whole into a file of its own.
  DataSource source = data_sources(a.data);
  std::vector<GivenOption> given;
  for (const auto& [option, cli] : a.added) {
    if (cli->count() == 0) continue;
    given.push_back({option, is_flag(*option) ? "" : text_of(*cli), std::string(option->flag)});
  }
  Model model = apply_options(given, file, source, a.options);
  return {std::move(model), std::move(source)};
}

void add_identify_arguments(CLI::App* sub, IdentifyArguments& a, const std::string& command) {
  sub->add_option("MODEL", a.model, "model file")->required();
  sub->add_option("DATA", a.data,
                  "data files (CSV, binary, .npy, .mat, HDF5), glob patterns or @LIST files "
                  "naming one per line, each file its own runs; - for standard input")
      ->required();
  sub->add_option("--format", a.format, "output format")->check(CLI::IsMember({"text", "json"}));
  add_stdin_limit(sub);
  for (const OptionDescription* option : options_of(command)) {
    const std::string flag(option->flag), fallback(option->default_text);
    const std::string help(std::string(option->help) +
                           (fallback.empty() ? "" : " (default: " + fallback + ")"));
    CLI::Option* added = nullptr;
    if (is_flag(*option)) {
      added = sub->add_flag(flag, help);
    } else {
      added = option->repeated ? sub->add_option(flag, a.lists.emplace_back(), help)
                               : sub->add_option(flag, a.single.emplace_back(), help);
      added->type_name(std::string(option->value_name))->default_str("");
    }
    a.added.emplace_back(option, added);
  }
  for (const auto& [option, cli] : a.added) {
    for (const std::string_view keyword : option->excludes) {
      const auto other = std::find_if(a.added.begin(), a.added.end(), [&](const auto& entry) {
        return entry.first->keyword == keyword;
      });
      if (other != a.added.end()) cli->excludes(other->second);
    }
  }
  // Under mpirun, the job's processes share the passes.
  a.options.identify.record.control.across_processes = true;
  sub->add_flag("-q,--quiet", a.quiet,
                "no progress on standard error (shown only on a terminal, never with JSON)");
}

}  // namespace momentid::cli
