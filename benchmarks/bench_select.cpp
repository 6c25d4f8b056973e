// `select` on a Duffing record (displacement with 5% noise and the force, no velocity) against
// the pass it follows, in the same run: the library of examples/select/library.mom (9 terms)
// identified on the lagged equations (one pass over the data), `select` of the same library
// (that pass, the scoring of every subset, the tests and the lag windows, then a second pass for
// the chosen model), and the chosen model identified alone (the second pass). What select adds
// beyond its two passes is the selection itself.
//
// Usage: bench_select [rows=1000000] [directory=/tmp] [repetitions=3]

#include <cstdio>
#include <cstdlib>
#include <string>

#include "momentid/identify.hpp"
#include "momentid/model.hpp"
#include "momentid/model_file.hpp"
#include "momentid/select.hpp"
#include "momentid/simulate.hpp"
#include "momentid/writer.hpp"
#include "timing.hpp"
#include "usage.hpp"

int main(int argc, char** argv) {
  if (asked_for_help(argc, argv,
                     "usage: bench_select [rows=1000000] [directory=/tmp] "
                     "[repetitions=3]"))
    return 0;
  const std::size_t rows = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000000;
  const std::string directory = argc > 2 ? argv[2] : "/tmp";
  const int repetitions = argc > 3 ? std::atoi(argv[3]) : 3;
  const std::string path = directory + "/bench_select.bin";
  {
    const momentid::Model duffing =
        momentid::parse_model_file(MOMENTID_SOURCE_DIR "/models/duffing.mom");
    momentid::SimulationOptions simulation;
    simulation.inputs = {momentid::InputSpec::parse("ma:K=10,w=0.1,sigma=20", "input")};
    simulation.samples = rows;
    simulation.burn_in = 2000;
    simulation.observe = {"y", "x"};
    simulation.noise = momentid::parse_noise({"y=0.05"});
    momentid::simulate_to_file(duffing, simulation, path, momentid::DataWriter::Format::kBinary);
  }
  const auto library = momentid::load_model(MOMENTID_SOURCE_DIR "/examples/select/library.mom");
  const momentid::DataSource source = momentid::DataSource::file(path);

  momentid::IdentifyOptions lagged;
  lagged.method = momentid::Method::kLagged;
  const double pass =
      median_seconds(repetitions, [&] { momentid::identify(*library, source, lagged); });
  momentid::SelectResult result;
  const double select =
      median_seconds(repetitions, [&] { result = momentid::select_terms(*library, source); });
  const momentid::Model chosen =
      momentid::parse_model(momentid::chosen_model_text(result), "chosen.mom");
  const double second =
      median_seconds(repetitions, [&] { momentid::identify(chosen, source, lagged); });
  std::remove(path.c_str());

  const double selection = select - pass - second;
  std::printf(
      "%zu rows of the Duffing model (y with 5%% noise, x), a library of %zu candidates, "
      "%zu subsets scored, median of %d\n",
      rows, result.candidates.size(), result.scored, repetitions);
  std::printf("%-34s %10s\n", "", "seconds");
  std::printf("%-34s %10.3f\n", "the library's pass (identify)", pass);
  std::printf("%-34s %10.3f  (%.2f times the library's pass)\n", "select", select, select / pass);
  std::printf("%-34s %10.3f\n", "the chosen model's pass (identify)", second);
  std::printf("%-34s %10.3f  (%.1f%% of the pass)\n", "the selection (the rest)", selection,
              100 * selection / pass);
}
