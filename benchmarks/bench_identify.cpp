// `identify` on a data file (derive, the pass that parses and accumulates, solve), on a CSV of N
// rows of the Duffing model, against a numpy baseline that loads the same file and computes the
// same moments, in the same run. Also the peak memory of the pass for N/10 and N rows.
//
// Usage: bench_identify [rows=10000000] [directory=/tmp] [--no-baseline]
//        bench_identify --pass FILE   (one pass; prints seconds and peak RSS; used internally)

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "momentid/derive.hpp"
#include "momentid/estimate.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "momentid/writer.hpp"

namespace {

const char* kModel = R"(model duffing
state y, v
input x
param c = 0.5, k = 4, eps = 1
y' = v
v' = -c*v - k*y - eps*y^3 + x
)";

std::vector<momentid::Monomial> moments(const momentid::Model& model) {
  momentid::DeriveOptions options;
  options.degree = 3;
  return momentid::moments_to_estimate(momentid::derive(model, options));
}

void write_data(const momentid::Model& model, const std::string& path, std::size_t rows) {
  momentid::SimulationOptions options;
  options.parameters = momentid::parameter_values(model, {});
  options.inputs = {momentid::InputSpec::parse("ma:K=10,w=0.1,sigma=20", "bench")};
  options.samples = rows;
  momentid::simulate_to_file(model, options, path, momentid::DataWriter::Format::kCsv);
}

int one_pass(const std::string& path) {
  const momentid::Model model = momentid::parse_model(kModel, "duffing.mom");
  const auto start = std::chrono::steady_clock::now();
  const momentid::IdentifyResult result =
      momentid::identify(model, momentid::DataSource::file(path), {.degree = 3});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("%.6f %ld %zu %zu\n", seconds, usage.ru_maxrss, result.data.rows,
              result.moments.size());
  return 0;
}

struct Pass {
  double seconds = 0;
  long peak_kib = 0;
  std::size_t rows = 0, moments = 0;
};

Pass run_pass(const std::string& self, const std::string& path) {
  std::string command = "'";
  command.append(self).append("' --pass '").append(path).append("'");
  FILE* pipe = popen(command.c_str(), "r");
  Pass p;
  if (pipe == nullptr ||
      std::fscanf(pipe, "%lf %ld %zu %zu", &p.seconds, &p.peak_kib, &p.rows, &p.moments) != 4) {
    std::fprintf(stderr, "bench_identify: the pass failed\n");
    std::exit(1);
  }
  pclose(pipe);
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--pass") return one_pass(argv[2]);
  const std::size_t rows = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 10000000;
  const std::filesystem::path dir = argc > 2 ? argv[2] : "/tmp";
  const bool baseline = !(argc > 3 && std::string(argv[3]) == "--no-baseline");
  const momentid::Model model = momentid::parse_model(kModel, "duffing.mom");
  const std::string big = (dir / "bench_identify_big.csv").string();
  const std::string small = (dir / "bench_identify_small.csv").string();
  write_data(model, big, rows);
  write_data(model, small, rows / 10);
  const double megabytes = static_cast<double>(std::filesystem::file_size(big)) / 1e6;

  const Pass small_pass = run_pass(argv[0], small);
  Pass pass = run_pass(argv[0], big);
  const Pass second = run_pass(argv[0], big);
  if (second.seconds < pass.seconds) pass = second;

  std::string numpy = "/usr/bin/python3 '" MOMENTID_SOURCE_DIR "/benchmarks/numpy_moments.py' '";
  numpy.append(big).append("' y,v x");
  for (const momentid::Monomial& m : moments(model)) {
    numpy.append(" ").append(std::to_string(m[0])).append(",").append(std::to_string(m[1]));
    numpy.append(",").append(std::to_string(m[2]));
  }
  double numpy_seconds = 0;
  if (FILE* pipe = baseline ? popen(numpy.c_str(), "r") : nullptr) {
    if (std::fscanf(pipe, "%lf", &numpy_seconds) != 1) numpy_seconds = 0;
    while (std::fgetc(pipe) != EOF) {
    }
    pclose(pipe);
  }
  std::filesystem::remove(big);
  std::filesystem::remove(small);

  std::printf("identify's pass over a CSV of the Duffing model (%zu moments), best of 2\n",
              pass.moments);
  std::printf("  %zu rows, %.0f MB: %.2f s, %.0f MB/s, %.2f M rows/s\n", pass.rows, megabytes,
              pass.seconds, megabytes / pass.seconds, pass.rows / pass.seconds / 1e6);
  if (numpy_seconds > 0) {
    std::printf(
        "  numpy baseline (loadtxt + the same moments): %.2f s, ratio numpy / momentid: "
        "%.1f\n",
        numpy_seconds, numpy_seconds / pass.seconds);
  } else {
    std::printf("  numpy baseline: not run%s\n",
                baseline ? " (it needs /usr/bin/python3 with numpy)" : " (--no-baseline)");
  }
  std::printf("  peak memory: %ld KiB for %zu rows, %ld KiB for %zu rows (ratio %.3f)\n",
              small_pass.peak_kib, small_pass.rows, pass.peak_kib, pass.rows,
              static_cast<double>(pass.peak_kib) / static_cast<double>(small_pass.peak_kib));
  return 0;
}
