#pragma once
// The subcommands of the momentid command line, one file each: each adds its options to the
// application and returns the function that runs it once the command line is parsed. Running
// returns the exit status (0 success, 3 nothing identifiable); errors are thrown.

#include <CLI/CLI.hpp>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "momentid/data_pass.hpp"
#include "momentid/model.hpp"
#include "momentid/moment.hpp"
#include "momentid/reader.hpp"
#include "momentid/validate.hpp"

namespace momentid::cli {

inline constexpr int kNothingIdentifiable = 3;

struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

Command add_derive(CLI::App& app);
Command add_simulate(CLI::App& app);
Command add_identify(CLI::App& app);
Command add_select(CLI::App& app);
Command add_check(CLI::App& app);
Command add_validate(CLI::App& app);
Command add_refine(CLI::App& app);
Command add_convert(CLI::App& app);

// The command-line option that sets the options field `field` (UsageError::option()): the flag
// of option_table()'s entry for the field ("fixed" is `--fix`, "hold" `--input-hold`), a flag
// as it is (`--lags`, the name a setter was given), or the field with `-` for `_`
// ("dt_from" `--dt-from`).
std::string flag_of(const std::string& field);

// Whether `path` is a readable model file (small enough to be one: at most 1 MB).
bool is_model_file(const std::string& path);
// The model at `model`; when that is not a model but `data` is, a UsageError saying that the
// files of `usage` (e.g. "identify MODEL DATA") were given in the wrong order.
Model model_argument(const std::string& model, const std::string& data, const std::string& usage);

// The layout options of option_table() (--skip-rows, --decimal, --missing, --names, --runs,
// --dt-from) for the commands that do not take identify's options, into `layout`.
void add_layout_options(CLI::App* command, FileLayout& layout);

// The options of the commands that drive a model with a record's inputs (validate, refine):
// --interpolation, --dt, --substeps, --columns and --center, the layout options and
// --stdin-limit. read_replay_arguments() is called in two steps: the columns before the model is
// completed by them (declare_derivative_columns), the rest with the completed model; it returns
// the channels --center names (`all`: every channel of the model).
struct ReplayArguments {
  std::string interpolation;
  std::optional<double> dt;
  std::vector<std::string> columns, center;
};
void add_replay_arguments(CLI::App* command, ReplayArguments& a, ReplayOptions& replay);
void read_replay_columns(const ReplayArguments& a, ReplayOptions& replay);
std::vector<std::string> read_replay_arguments(const ReplayArguments& a, const Model& model,
                                               ReplayOptions& replay);

// --threads and --shard-size, into `control`.
void add_pass_options(CLI::App* command, PassControl& control);

// --stdin-limit: the most bytes stored from standard input (DataSource::standard_input), which
// data_source() and data_sources() read with.
void add_stdin_limit(CLI::App* command);
// The data argument: a file, or standard input for `-`.
DataSource data_source(const std::string& path);
// The data of several arguments: files, glob patterns (`runs/*.h5`) and `@LIST` files that name
// one file (or pattern) per line (blank lines and `#` lines skipped), in order; `-` alone is
// standard input. Throws UsageError for a pattern that matches nothing or an unreadable list.
DataSource data_sources(const std::vector<std::string>& arguments);
// `--columns v=velocity,x=force`: the model's names mapped to the data's columns.
std::map<std::string, std::string> column_map(const std::vector<std::string>& entries);
// `--input-hold`: nullopt when not given (empty).
std::optional<InputHold> hold_option(const std::string& text);
// `--measured y,x`: flags over the model's variables.
std::vector<bool> variable_flags(const Model& model, const std::vector<std::string>& names,
                                 const std::string& option);

}  // namespace momentid::cli
