// The momentid command line: maps options to library calls and prints. Exit status: 0 success,
// 1 usage error, 2 bad model or data, 3 nothing identifiable.

#include <CLI/CLI.hpp>
#include <iostream>

#include "derive/moment_system.hpp"
#include "model/model.hpp"

namespace {

constexpr int kNothingIdentifiable = 3;

struct DeriveCommand {
  std::string model;
  std::string multipliers;
  int degree = 0;
  std::string format = "text";
};

int run_derive(const DeriveCommand& command) {
  const momentid::Model model = momentid::parse_model_file(command.model);
  momentid::DeriveOptions options;
  if (!command.multipliers.empty()) {
    options.multipliers =
        momentid::parse_multiplier_list(model, command.multipliers, "--multipliers");
  }
  options.degree = command.degree;
  const momentid::MomentSystem system = momentid::derive(model, options);
  if (command.format == "latex") {
    std::cout << momentid::format_latex(system);
  } else if (command.format == "json") {
    std::cout << momentid::format_json(system);
  } else {
    std::cout << momentid::format_text(system);
  }
  if (system.equations.empty()) {
    std::cerr << "momentid: no moment equation could be derived for " << command.model << "\n";
    return kNothingIdentifiable;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"momentid: identify the parameters of polynomial ODE models from random data"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "momentid 0.1.0");

  DeriveCommand derive;
  CLI::App* derive_app = app.add_subcommand(
      "derive", "print the moment equations of a model: a linear system in its parameters");
  derive_app->add_option("MODEL", derive.model, "model file")->required();
  auto* multipliers = derive_app->add_option(
      "--multipliers", derive.multipliers,
      "comma-separated monomials in the states to multiply every equation by, e.g. \"y, v, y^3\"");
  derive_app
      ->add_option("--degree", derive.degree,
                   "multiply by every monomial in the states of degree 1..D")
      ->check(CLI::Range(1, 12))
      ->excludes(multipliers);
  derive_app->add_option("--format", derive.format, "output format")
      ->check(CLI::IsMember({"text", "latex", "json"}));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);
    return status == 0 ? 0 : 1;
  }

  try {
    if (derive_app->parsed()) return run_derive(derive);
  } catch (const momentid::LocatedError& e) {
    std::cerr << momentid::render_with_caret(e) << "\n";
    return e.exit_code();
  } catch (const momentid::Error& e) {
    std::cerr << "momentid: " << e.what() << "\n";
    return e.exit_code();
  }
  return 0;
}
