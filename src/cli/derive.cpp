// momentid derive MODEL [--multipliers LIST | --degree D] [--format text|latex|json]

#include "momentid/derive.hpp"

#include <iostream>
#include <memory>
#include <tuple>

#include "cli/commands.hpp"
#include "momentid/lagged.hpp"
#include "momentid/latent.hpp"
#include "momentid/model.hpp"
#include "momentid/option_table.hpp"
#include "momentid/writer.hpp"

namespace momentid::cli {
namespace {

struct DeriveCommand {
  std::string model;
  std::optional<std::string> multipliers;
  int degree = 0;
  std::string format = "text";
  std::optional<std::string> lags;
  std::optional<std::string> instruments;
  std::vector<std::string> measured;
};

int run_lagged(const DeriveCommand& command, const Model& model) {
  LagOptions options;
  std::tie(options.first_lag, options.last_lag) = parse_lag_range(*command.lags, "--lags");
  if (command.instruments) {
    options.instruments = parse_instrument_list(model, *command.instruments, "--instruments");
  }
  if (!command.measured.empty()) {
    options.measured = variable_flags(model, command.measured, "--measured");
    const Elimination elimination = eliminate_latent(model, options.measured);
    if (!elimination.latent.empty()) {
      if (command.format == "latex") {
        throw UsageError("format",
                         "the elimination of latent states prints as text or json, not latex");
      }
      write_whole_file("-", command.format == "json" ? format_json(model, elimination)
                                                     : format_text(model, elimination));
      return 0;
    }
  }
  const LaggedSystem system = derive_lagged(model, options);
  write_whole_file("-", command.format == "latex"  ? format_latex(system)
                        : command.format == "json" ? format_json(system)
                                                   : format_text(system));
  if (system.equations.empty()) {
    std::cerr << "momentid: no lagged moment equation could be derived for " << command.model
              << "\n";
    return kNothingIdentifiable;
  }
  return 0;
}

int run_derive(const DeriveCommand& command) {
  const Model model = parse_model_file(command.model);
  if (command.lags) return run_lagged(command, model);
  DeriveOptions options;
  if (command.multipliers) {
    options.multipliers = parse_multiplier_list(model, *command.multipliers, "--multipliers");
  }
  options.degree = command.degree;
  const MomentSystem system = derive(model, options);
  write_whole_file("-", command.format == "latex"  ? format_latex(system)
                        : command.format == "json" ? format_json(system)
                                                   : format_text(system));
  if (system.equations.empty()) {
    std::cerr << "momentid: no moment equation could be derived for " << command.model
              << (model.parameters().empty() ? ": the model has no unknown parameters" : "")
              << "\n";
    return kNothingIdentifiable;
  }
  return 0;
}

}  // namespace

Command add_derive(CLI::App& app) {
  auto command = std::make_shared<DeriveCommand>();
  CLI::App* sub = app.add_subcommand(
      "derive", "print the moment equations of a model: a linear system in its parameters");
  sub->add_option("MODEL", command->model, "model file")->required();
  auto* multipliers = sub->add_option(
      "--multipliers", command->multipliers,
      "comma-separated monomials in the states to multiply every equation by, e.g. \"y, v, y^3\"");
  sub->add_option("--degree", command->degree,
                  "multiply by every monomial in the states of degree 1..D")
      ->check(CLI::Range(1, 12))
      ->excludes(multipliers);
  sub->add_option("--format", command->format, "output format")
      ->check(CLI::IsMember({"text", "latex", "json"}));
  auto* lags =
      sub->add_option("--lags", command->lags,
                      "lagged equations: instruments at lags FIRST..LAST samples, e.g. 3..40")
          ->excludes(multipliers);
  sub->add_option("--instruments", command->instruments,
                  "instruments for --lags: monomials in the measured channels, e.g. \"y, y^3\"")
      ->needs(lags);
  sub->add_option("--measured", command->measured,
                  "the channels the data have, for --lags (default: every state and input)")
      ->delimiter(',')
      ->needs(lags);
  return {sub, [command] { return run_derive(*command); }};
}

}  // namespace momentid::cli
