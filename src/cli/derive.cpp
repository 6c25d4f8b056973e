// momentid derive MODEL [--multipliers LIST | --degree D] [--format text|latex|json]

#include "momentid/derive.hpp"

#include <iostream>
#include <memory>

#include "cli/commands.hpp"
#include "momentid/model.hpp"

namespace momentid::cli {
namespace {

struct DeriveCommand {
  std::string model;
  std::optional<std::string> multipliers;
  int degree = 0;
  std::string format = "text";
};

int run_derive(const DeriveCommand& command) {
  const Model model = parse_model_file(command.model);
  DeriveOptions options;
  if (command.multipliers) {
    options.multipliers = parse_multiplier_list(model, *command.multipliers, "--multipliers");
  }
  options.degree = command.degree;
  const MomentSystem system = derive(model, options);
  if (command.format == "latex") {
    std::cout << format_latex(system);
  } else if (command.format == "json") {
    std::cout << format_json(system);
  } else {
    std::cout << format_text(system);
  }
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
  return {sub, [command] { return run_derive(*command); }};
}

}  // namespace momentid::cli
