// `validate` on a Duffing record against `simulate` of the same length, in the same run: the
// time to write the record with simulate_to_file, and to validate the model on it (read, replay,
// choose the skip, compare, correlate), for CSV and binary files.
//
// Usage: bench_validate [rows=1000000] [directory=/tmp] [repetitions=3]

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "momentid/validate.hpp"
#include "timing.hpp"
#include "usage.hpp"

int main(int argc, char** argv) {
  if (asked_for_help(argc, argv,
                     "usage: bench_validate [rows=1000000] [directory=/tmp] [repetitions=3]"))
    return 0;
  const std::size_t rows = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000000;
  const std::string directory = argc > 2 ? argv[2] : "/tmp";
  const int repetitions = argc > 3 ? std::atoi(argv[3]) : 3;
  const momentid::Model model =
      momentid::parse_model_file(MOMENTID_SOURCE_DIR "/models/duffing.mom");
  momentid::SimulationOptions simulation;
  simulation.inputs = {momentid::InputSpec::parse("ma:K=10,w=0.1,sigma=20", "input")};
  simulation.samples = rows;
  simulation.burn_in = 2000;
  // The model's own values: a consistent model, whose trajectory and noise band judge it (a
  // wrong one would add the statistics' simulations).
  const momentid::ValidateOptions validation;
  std::printf("%zu rows of the Duffing model, median of %d\n", rows, repetitions);
  std::printf("%-8s %12s %12s %8s %10s %11s\n", "format", "simulate s", "validate s", "ratio",
              "fit %", "consistent");
  for (const auto& [name, writer_format] :
       {std::pair{"csv", momentid::DataWriter::Format::kCsv},
        std::pair{"bin", momentid::DataWriter::Format::kBinary}}) {
    const auto format = writer_format;  // a lambda may not capture a structured binding (clang 14)
    const std::string path = directory + "/bench_validate." + name;
    const double simulate = median_seconds(
        repetitions, [&] { momentid::simulate_to_file(model, simulation, path, format); });
    double fit = 0;
    bool consistent = false;
    const double validate = median_seconds(repetitions, [&] {
      const momentid::ValidateResult result =
          momentid::validate(model, momentid::DataSource::file(path), validation);
      fit = result.outputs.front().fit;
      consistent = result.consistent;
    });
    std::printf("%-8s %12.3f %12.3f %8.2f %10.3f %11s\n", name, simulate, validate,
                validate / simulate, fit, consistent ? "yes" : "no");
    std::remove(path.c_str());
  }
}
