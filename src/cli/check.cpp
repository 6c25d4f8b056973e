// momentid check DATA [MODEL] [--lags L] [--input-hold H] [--columns NAME=COLUMN,...]
//                [--format text|json]

#include "momentid/check.hpp"

#include <memory>
#include <utility>

#include "cli/commands.hpp"
#include "cli/progress.hpp"
#include "momentid/model.hpp"
#include "momentid/writer.hpp"

namespace momentid::cli {
namespace {

struct CheckCommand {
  std::vector<std::string> data;  // the model, if any, among them
  bool quiet = false;
  CheckOptions options;
  std::string hold;
  std::vector<std::string> columns;
  std::string format = "text";
};

int run_check(CheckCommand& command) {
  std::optional<Model> model;
  // The model is the last argument, or the first (`check MODEL DATA`), when it is one.
  std::vector<std::string>& files = command.data;
  if (files.size() > 1 && is_model_file(files.back())) {
    model = parse_model_file(files.back());
    files.pop_back();
  } else if (files.size() > 1 && is_model_file(files.front())) {
    model = parse_model_file(files.front());
    files.erase(files.begin());
  } else if (files.size() == 2) {
    model = parse_model_file(files.back());  // reports why it is no model
    files.pop_back();
  }
  command.options.record.hold = hold_option(command.hold);
  command.options.record.columns = column_map(command.columns);
  // Once: a pipe or standard input is read whole into a file of its own.
  const DataSource source = data_sources(files);
  if (model) model = declare_derivative_columns(*model, command.options.record, source);
  TerminalProgress progress(!command.quiet && command.format != "json");
  command.options.record.control.progress = progress.callback();
  const CheckResult result = check(source, model ? &*model : nullptr, command.options);
  progress.finish();
  write_whole_file("-", command.format == "json" ? format_json(result) : format_text(result));
  return 0;
}

}  // namespace

Command add_check(CLI::App& app) {
  auto command = std::make_shared<CheckCommand>();
  CLI::App* sub = app.add_subcommand(
      "check", "statistics of a data file: autocorrelations, smoothness, stationarity");
  sub->add_option("DATA", command->data,
                  "data files (globs and @LIST files too), then optionally a model file whose "
                  "stationarity identities to check; - for standard input")
      ->required();
  sub->add_option("--lags", command->options.lags, "autocorrelation lags")
      ->check(CLI::Range(std::size_t{1}, CheckOptions::kMaxLags));
  sub->add_option("--input-hold", command->hold, "how the inputs were sampled")
      ->check(CLI::IsMember(names_of<InputHold>()));
  sub->add_option("--dt", command->options.record.dt,
                  "sample interval, overriding the data's: the time column is then not read")
      ->check(CLI::PositiveNumber);
  sub->add_option("--columns", command->columns, "NAME=COLUMN: where a model variable is");
  sub->add_option("--format", command->format, "output format")
      ->check(CLI::IsMember({"text", "json"}));
  add_layout_options(sub, command->options.record.layout);
  add_stdin_limit(sub);
  add_pass_options(sub, command->options.record.control);
  sub->add_flag("-q,--quiet", command->quiet,
                "no progress on standard error (shown only on a terminal)");
  return {sub, [command] { return run_check(*command); }};
}

}  // namespace momentid::cli
