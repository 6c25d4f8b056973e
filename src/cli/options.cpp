#include <glob.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "cli/commands.hpp"
#include "momentid/error.hpp"
#include "momentid/option_table.hpp"

namespace momentid::cli {

std::string flag_of(const std::string& field) {
  // A name that a setter of the option table was given is spelled already.
  if (field.starts_with("-")) return field;
  // The fields of other commands' options that have another name.
  static const std::map<std::string, std::string> kFlags = {
      {"inputs", "--input"},
      {"parameters", "--set"},
      // Its messages (that the data do not allow it) have always named it bare.
      {"extrapolate", "extrapolate"}};
  if (const auto found = kFlags.find(field); found != kFlags.end()) return found->second;
  if (const OptionDescription* option = option_of_field(field)) return std::string(option->flag);
  std::string flag = "--" + field;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

bool is_model_file(const std::string& path) {
  std::error_code error;
  if (path == "-" || !std::filesystem::is_regular_file(path, error) ||
      std::filesystem::file_size(path, error) > (1u << 20)) {
    return false;
  }
  try {
    parse_model_file(path);
    return true;
  } catch (const Error&) {
    return false;
  }
}

Model model_argument(const std::string& model, const std::string& data, const std::string& usage) {
  try {
    return parse_model_file(model);
  } catch (const LocatedError&) {
    if (is_model_file(data)) {
      throw UsageError("'" + model + "' is not a model file but '" + data +
                       "' is: did you swap the files? The order is " + usage);
    }
    throw;
  }
}

void add_pass_options(CLI::App* command, PassControl& control) {
  // Under mpirun, the job's processes share the passes.
  control.across_processes = true;
  command
      ->add_option("--threads", control.threads,
                   "threads reading the data at once (default 0: one per core)")
      ->check(CLI::Range(0, 1024));
  command
      ->add_option("--shard-size", control.shard_bytes,
                   "cut files into shards of about this size, read in parallel (default 16M; "
                   "k, M, G for powers of 1024)")
      ->transform(CLI::AsSizeValue(false))
      ->check(CLI::Validator(
          [](std::string& bytes) {
            // The value arrives in bytes, converted from the units.
            return std::stoull(bytes) >= 1024
                       ? std::string()
                       : "expected at least 1k (1024 bytes), found " + bytes + " bytes";
          },
          "SIZE"));
}

void add_layout_options(CLI::App* command, FileLayout& layout) {
  command->add_option("--skip-rows", layout.skip_rows,
                      "lines after the header that are not data (descriptions), skipped; a units "
                      "row is skipped without it");
  command
      ->add_option_function<std::string>(
          "--decimal", [&layout](const std::string& text) { layout.decimal = text[0]; },
          "the decimal separator, . or , (with ; or blank separated fields)")
      ->check(CLI::IsMember({".", ","}));
  std::map<std::string, MissingValues> rules;
  for (const std::string& name : names_of<MissingValues>()) {
    rules[name] = parse_missing_values(name, "missing");
  }
  command
      ->add_option("--missing", layout.missing,
                   "a missing value (empty, nan, NA): error, drop-row (joins its neighbours) or "
                   "split-run (starts a new run)")
      ->transform(CLI::CheckedTransformer(rules))
      ->default_str(to_string(MissingValues::kError));
  command
      ->add_option("--names", layout.column_names,
                   "names for the columns of a 2-D .npy array, in order")
      ->delimiter(',');
  command
      ->add_option("--runs", layout.runs,
                   "runs in one .mat or HDF5 file: prefixes of each run's channels, e.g. "
                   "run1/,run2/ (HDF5 groups) or a_,b_ (variables a_y, b_y)")
      ->delimiter(',');
  command->add_option("--dt-from", layout.dt_from,
                      "the sample interval from a scalar in a .mat or HDF5 file: NAME, or 1/NAME "
                      "for a rate");
}

namespace {
std::uint64_t g_stdin_limit = DataSource::kStoredLimit;
}  // namespace

void add_stdin_limit(CLI::App* command) {
  command
      ->add_option("--stdin-limit", g_stdin_limit,
                   "the most bytes stored from standard input (-), with k, M or G for powers of "
                   "1024 (default: 16G)")
      ->transform(CLI::AsSizeValue(false));
}

DataSource data_source(const std::string& path) {
  return path == "-" ? DataSource::standard_input(g_stdin_limit) : DataSource::file(path);
}

namespace {

void add_paths(const std::string& argument, std::vector<std::string>& out, int depth) {
  if (argument.starts_with('@') && argument.size() > 1 && depth < 8) {
    std::ifstream list(argument.substr(1));
    if (!list) throw UsageError("cannot read the list file '" + argument.substr(1) + "'");
    std::string line;
    while (std::getline(list, line)) {
      const std::size_t begin = line.find_first_not_of(" \t\r");
      if (begin == std::string::npos || line[begin] == '#') continue;
      const std::size_t end = line.find_last_not_of(" \t\r");
      add_paths(line.substr(begin, end - begin + 1), out, depth + 1);
    }
    return;
  }
  if (argument.find_first_of("*?[") == std::string::npos) {
    out.push_back(argument);
    return;
  }
  glob_t found{};
  const int status = glob(argument.c_str(), 0, nullptr, &found);
  if (status != 0) {
    globfree(&found);
    throw UsageError("no file matches '" + argument + "'");
  }
  for (std::size_t i = 0; i < found.gl_pathc; ++i) out.emplace_back(found.gl_pathv[i]);
  globfree(&found);
}

}  // namespace

DataSource data_sources(const std::vector<std::string>& arguments) {
  if (arguments.size() == 1 && arguments.front() == "-") {
    return DataSource::standard_input(g_stdin_limit);
  }
  std::vector<std::string> paths;
  for (const std::string& argument : arguments) {
    if (argument == "-") throw UsageError("- (standard input) must be the only data argument");
    add_paths(argument, paths, 0);
  }
  if (paths.empty()) throw UsageError("the data arguments name no file");
  return DataSource::files(std::move(paths));
}

std::map<std::string, std::string> column_map(const std::vector<std::string>& entries) {
  std::map<std::string, std::string> out;
  for (const std::string& e : entries) {
    for (const auto& pair : parse_option_pairs(e, "--columns", "NAME=COLUMN"))
      out.insert_or_assign(pair.first, pair.second);
  }
  return out;
}

std::optional<InputHold> hold_option(const std::string& text) {
  if (text.empty()) return std::nullopt;
  return parse_input_hold(text, "hold");
}

std::vector<bool> variable_flags(const Model& model, const std::vector<std::string>& names,
                                 const std::string& option) {
  std::vector<bool> out(model.variables().size(), false);
  for (const std::string& name : names) {
    const int v = model.variable_index(name);
    if (v < 0) throw UsageError(option + ": '" + name + "' is not a state or input of the model");
    out[static_cast<std::size_t>(v)] = true;
  }
  return out;
}

void add_replay_arguments(CLI::App* command, ReplayArguments& a, ReplayOptions& replay) {
  command->add_option("--interpolation", a.interpolation,
                      "the inputs between samples: zoh, foh, cubic or sinc (default: zoh for "
                      "held inputs, sinc otherwise)");
  command->add_option("--dt", a.dt, "sample interval, overriding the data's");
  command
      ->add_option("--substeps", replay.substeps,
                   "Runge-Kutta steps per sample interval (default: the fewest that change the "
                   "result by less than 1e-6)")
      ->check(CLI::Range(1, RecordSimulator::kMaxSubsteps));
  command->add_option("--columns", a.columns, "NAME=COLUMN: where a model variable is");
  command
      ->add_option("--center", a.center,
                   "remove the means of these channels (NAME,... or all) before simulating and "
                   "comparing: a sensor offset on a symmetric system")
      ->delimiter(',');
  add_layout_options(command, replay.record.layout);
  add_stdin_limit(command);
}

void read_replay_columns(const ReplayArguments& a, ReplayOptions& replay) {
  replay.record.columns = column_map(a.columns);
}

std::vector<std::string> read_replay_arguments(const ReplayArguments& a, const Model& model,
                                               ReplayOptions& replay) {
  if (!a.interpolation.empty()) {
    replay.interpolation = parse_interpolation(a.interpolation, "interpolation");
  }
  replay.record.dt = a.dt;
  return a.center.size() == 1 && a.center[0] == "all" ? model.channel_names() : a.center;
}

}  // namespace momentid::cli
