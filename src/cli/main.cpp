// The momentid command line: maps options to library calls and prints. Exit status: 0 success,
// 1 usage error, 2 bad model or data, 3 nothing identifiable.

#include <CLI/CLI.hpp>
#include <iostream>
#include <vector>

#include "cli/commands.hpp"
#include "momentid/convert.hpp"
#include "momentid/error.hpp"
#include "momentid/version.hpp"
#include "momentid/writer.hpp"

#if defined(__SANITIZE_ADDRESS__)
// CLN allocates a few bytes at start-up that it never frees; that is not momentid's leak.
extern "C" const char* __lsan_default_suppressions() { return "leak:libcln.so\n"; }
extern "C" const char* __lsan_default_options() { return "print_suppressions=0"; }
#endif

int main(int argc, char** argv) {
  momentid::remove_partial_output_on_interrupt();
  CLI::App app{"momentid: identify the parameters of polynomial ODE models from random data"};
  app.require_subcommand(1);
  // --help shows each option's default (subcommands inherit this).
  app.option_defaults()->always_capture_default();
  app.set_version_flag("-V,--version",
                       "momentid " MOMENTID_VERSION "\ndata formats: " + momentid::data_formats() +
                           "\nvalidate plots: SVG (written by momentid)"
                           "\ndistributions: Boost.Math; linear algebra: Eigen; algebra: GiNaC");

  const std::vector<momentid::cli::Command> commands{
      momentid::cli::add_derive(app),   momentid::cli::add_simulate(app),
      momentid::cli::add_identify(app), momentid::cli::add_check(app),
      momentid::cli::add_validate(app), momentid::cli::add_convert(app)};

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);
    return status == 0 ? 0 : 1;
  }

  try {
    for (const momentid::cli::Command& command : commands) {
      if (command.app->parsed()) return command.run();
    }
  } catch (const momentid::LocatedError& e) {
    std::cerr << momentid::render_with_caret(e) << "\n";
    return e.exit_code();
  } catch (const momentid::Error& e) {
    std::cerr << "momentid: " << momentid::printable(e.what()) << "\n";
    return e.exit_code();
  } catch (const std::exception& e) {
    // Everything momentid checks is reported above; this is a failure it did not foresee.
    std::cerr << "momentid: internal error: " << momentid::printable(e.what()) << "\n";
    return 2;
  }
  return 0;
}
