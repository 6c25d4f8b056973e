// The momentid command line: maps options to library calls and prints. Exit status: 0 success,
// 1 usage error, 2 bad model or data, 3 nothing identifiable.

#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <vector>

#include "cli/commands.hpp"
#include "common/cluster.hpp"
#include "data/array_writers.hpp"
#include "momentid/convert.hpp"
#include "momentid/error.hpp"
#include "momentid/version.hpp"
#include "momentid/writer.hpp"

#if defined(__SANITIZE_ADDRESS__)
// CLN allocates a few bytes at start-up that it never frees; that is not momentid's leak.
extern "C" const char* __lsan_default_suppressions() { return "leak:libcln.so\n"; }
extern "C" const char* __lsan_default_options() { return "print_suppressions=0"; }
#endif

namespace {

// The message of an error as the command line shows it, from `who`: a located error begins with
// its place, unless it is one process's of several.
std::string message_of(const std::exception& e, const std::string& who = "momentid") {
  const std::string lead = who + ": ";
  if (const auto* located = dynamic_cast<const momentid::LocatedError*>(&e)) {
    return (who == "momentid" ? "" : lead) +
           momentid::render_with_caret(*located, momentid::cli::flag_of);
  }
  if (const auto* usage = dynamic_cast<const momentid::UsageError*>(&e)) {
    return lead + momentid::printable(usage->text(momentid::cli::flag_of));
  }
  if (dynamic_cast<const momentid::Error*>(&e) != nullptr) {
    return lead + momentid::printable(e.what());
  }
  // Everything momentid checks is reported above; this is a failure it did not foresee.
  return lead + "internal error: " + momentid::printable(e.what());
}

int exit_code_of(const std::exception& e) {
  const auto* error = dynamic_cast<const momentid::Error*>(&e);
  return error != nullptr ? error->exit_code() : 2;
}

// The program's memory, before anything large is allocated. A lagged pass of 10^5 rows keeps
// thousands of stretches of sums, each as long as its thousands of moments, then batch series
// as large: about 100 MB touched once, a page fault every 4 KiB, each costly on a virtual
// machine (a third of the identification's time where this was measured). So the pass's
// threads take their memory from the main heap, where the solve after them finds it again,
// rather than from arenas of their own; large blocks come from the heap too, which keeps what
// is freed; and the heap grows 256 MiB at a time, its first growth advised as transparent huge
// pages of 2 MiB (taken where the kernel gives them on request; elsewhere the advice is
// ignored). See docs/benchmarks.md.
void prepare_memory() {
  mallopt(M_ARENA_MAX, 1);
  constexpr int kGrowth = 256 << 20;
  mallopt(M_MMAP_THRESHOLD, kGrowth);
  mallopt(M_TRIM_THRESHOLD, 2 * kGrowth);
  mallopt(M_TOP_PAD, kGrowth);
  const auto start = reinterpret_cast<std::uintptr_t>(sbrk(0));
  // Extends the heap by the growth. Kept in a volatile: a block freed unused is otherwise no
  // allocation at all to the compiler, and the heap then grew later, without the advice.
  void* volatile grow = std::malloc(1 << 20);
  const auto end = reinterpret_cast<std::uintptr_t>(sbrk(0));
  constexpr std::uintptr_t kHugePage = 2 << 20;
  const std::uintptr_t first = (start + kHugePage - 1) & ~(kHugePage - 1);
  if (end > first) madvise(reinterpret_cast<void*>(first), end - first, MADV_HUGEPAGE);
  std::free(grow);
}

}  // namespace

int main(int argc, char** argv) {
  prepare_memory();
  // Under mpirun, the processes of the job share each pass over the data (identify, check);
  // the first prints, the others are silent.
  momentid::data::quiet_array_libraries();
  const momentid::cluster::Session mpi(argc, argv);
  const int rank = momentid::cluster::rank();
  const bool several = momentid::cluster::size() > 1;
  const int errors_fd = several ? dup(STDERR_FILENO) : STDERR_FILENO;
  if (several && rank != 0) {
    if (std::freopen("/dev/null", "w", stdout) == nullptr ||
        std::freopen("/dev/null", "w", stderr) == nullptr) {
      momentid::cluster::abort(2);
    }
  }

  momentid::remove_partial_output_on_interrupt();
  CLI::App app{"momentid: identify the parameters of polynomial ODE models from random data"};
  app.require_subcommand(1);
  // --help shows each option's default (subcommands inherit this).
  app.option_defaults()->always_capture_default();
  const std::string mpi_library = momentid::cluster::library();
  app.set_version_flag(
      "-V,--version",
      "momentid " MOMENTID_VERSION "\ndata formats: " + momentid::data_formats() +
          "\nvalidate plots: SVG (written by momentid)"
          "\ndistributions: Boost.Math; linear algebra: Eigen; algebra: GiNaC; nonlinear least "
          "squares: Ceres Solver" +
          (mpi_library.empty() ? std::string()
                               : "\nMPI: " + mpi_library + ", passes shared under mpirun"));

  const std::vector<momentid::cli::Command> commands{
      momentid::cli::add_derive(app),   momentid::cli::add_simulate(app),
      momentid::cli::add_identify(app), momentid::cli::add_select(app),
      momentid::cli::add_check(app),    momentid::cli::add_validate(app),
      momentid::cli::add_refine(app),   momentid::cli::add_convert(app)};

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);
    return status == 0 ? 0 : 1;
  }

  try {
    for (const momentid::cli::Command& command : commands) {
      if (!command.app->parsed()) continue;
      const std::string name = command.app->get_name();
      if (several && name != "identify" && name != "check") {
        throw momentid::UsageError(
            "under mpirun only identify and check share their work among "
            "processes: run " +
            name + " as one process");
      }
      return command.run();
    }
  } catch (const std::exception& e) {
    const std::string text = message_of(e);
    if (!several) {
      std::cerr << text << "\n";
      return exit_code_of(e);
    }
    // Every process fails alike (the same model or data error): the first says it, and the
    // others' messages where they differ.
    if (const auto all = momentid::cluster::all_failed(text, std::chrono::seconds(1))) {
      for (std::size_t r = 0; r < all->size(); ++r) {
        if (r == 0 || (*all)[r] != all->front()) {
          std::cerr << (r == 0 ? "" : "process " + std::to_string(r) + ": ") << (*all)[r] << "\n";
        }
      }
      return exit_code_of(e);
    }
    // This process alone fails, and the others may wait for it: it says so, and ends them all.
    const std::string alone =
        message_of(e, "momentid (process " + std::to_string(rank) + ")") + "\n";
    if (write(errors_fd, alone.data(), alone.size()) < 0) {
      // Nowhere left to say it.
    }
    momentid::cluster::abort(exit_code_of(e));
  }
  return 0;
}
