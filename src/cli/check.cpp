// momentid check DATA [MODEL] [--lags L] [--input-hold H] [--columns NAME=COLUMN,...]

#include "momentid/check.hpp"

#include <iostream>
#include <memory>
#include <utility>

#include "cli/commands.hpp"
#include "momentid/model.hpp"

namespace momentid::cli {
namespace {

struct CheckCommand {
  std::string data;
  std::string model;
  CheckOptions options;
  std::string hold;
  std::vector<std::string> columns;
};

int run_check(CheckCommand& command) {
  std::optional<Model> model;
  // Either order: `check MODEL DATA` is read as `check DATA MODEL`.
  if (!command.model.empty() && !is_model_file(command.model) && is_model_file(command.data)) {
    std::swap(command.model, command.data);
  }
  if (!command.model.empty()) model = parse_model_file(command.model);
  command.options.hold = hold_option(command.hold);
  command.options.columns = column_map(command.columns);
  const CheckResult result =
      check(data_source(command.data), model ? &*model : nullptr, command.options);
  std::cout << format_text(result);
  return 0;
}

}  // namespace

Command add_check(CLI::App& app) {
  auto command = std::make_shared<CheckCommand>();
  CLI::App* sub = app.add_subcommand(
      "check", "statistics of a data file: autocorrelations, smoothness, stationarity");
  sub->add_option("DATA", command->data, "data file (CSV or binary), - for standard input")
      ->required();
  sub->add_option("MODEL", command->model, "model file: check its stationarity identities");
  sub->add_option("--lags", command->options.lags, "autocorrelation lags")
      ->check(CLI::Range(std::size_t{1}, CheckOptions::kMaxLags));
  sub->add_option("--input-hold", command->hold, "how the inputs were sampled")
      ->check(CLI::IsMember({"sample", "zoh"}));
  sub->add_option("--dt", command->options.dt,
                  "sample interval, overriding the data's: the time column is then not read")
      ->check(CLI::PositiveNumber);
  sub->add_option("--columns", command->columns, "NAME=COLUMN: where a model variable is");
  add_layout_options(sub, command->options.layout);
  return {sub, [command] { return run_check(*command); }};
}

}  // namespace momentid::cli
