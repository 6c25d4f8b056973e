// `identify` on a data file (derive, the pass that parses and accumulates, solve), on a CSV and a
// binary file of N rows of the Duffing model, each against the reading floor of the same file
// on as many threads as the pass (the CSV: every field parsed by std::from_chars and summed; the
// binary file: every double read and summed), and the CSV against a numpy baseline that loads
// it and computes the same moments, in the same run. Also the peak memory of the pass for N/10
// and N rows, the lagged pass against the zero-lag one, a latent state and its refinement, and a
// state formed from its acceleration against the same run's measured displacement.
//
// Usage: bench_identify [rows=10000000] [directory=/tmp] [--no-baseline]
//        bench_identify --pass FILE   (one pass; prints seconds and peak RSS; used internally)

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "momentid/derive.hpp"
#include "momentid/estimate.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "momentid/writer.hpp"
#include "timing.hpp"
#include "usage.hpp"

namespace {

const char* kModel = R"(model duffing
state y, v
input x
param c = 0.5, k = 4, eps = 1
y' = v
v' = -c*v - k*y - eps*y^3 + x
)";

// The Duffing oscillator behind an input filter, whose output z a record of y and x leaves latent
// (models/filtered_duffing.mom).
const char* kFiltered = R"(model filtered_duffing
state y, v, z
input x
param c = 0.5, k = 4, eps = 1, a = 2, g = 1
const b = 2
y' = v
v' = -c*v - k*y - eps*y^3 + g*z
z' = -a*z + b*x
)";

// The Duffing oscillator seen through an accelerometer (models/duffing_accelerometer.mom): from a
// record of a and x, identify forms y inside a high-pass and takes out the misfit the filter
// leaves in y^3, from a simulation of the identified model and a second pass over it.
const char* kAccelerometer = R"(model duffing_accelerometer
state y, v
input x
measured a = v'
param c = 0.5, k = 4, eps = 1
y' = v
v' = -c*v - k*y - eps*y^3 + x
)";

std::vector<momentid::Monomial> moments(const momentid::Model& model) {
  momentid::DeriveOptions options;
  options.degree = 3;
  return momentid::moments_to_estimate(momentid::derive(model, options));
}

// `observe`: the columns to write (empty: all); `input`: the force's process.
void write_data(const momentid::Model& model, const std::string& path, std::size_t rows,
                std::vector<std::string> observe = {},
                momentid::FileFormat format = momentid::FileFormat::kCsv,
                const std::string& input = "ma:K=10,w=0.1,sigma=20") {
  momentid::SimulationOptions options;
  options.inputs = {momentid::InputSpec::parse(input, "bench")};
  options.samples = rows;
  options.observe = std::move(observe);
  momentid::simulate_to_file(model, options, path, format);
}

// The reading floor of `path` (in the page cache) on `threads` threads, each taking a contiguous
// part of the bytes past `header_bytes`: the seconds to sum every double (binary) or to parse
// every field of every line that starts in the part with std::from_chars and sum it (CSV).
double reading_floor(const std::string& path, bool csv, std::size_t header_bytes,
                     std::size_t threads) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return 0;
  const auto size = static_cast<std::size_t>(std::filesystem::file_size(path));
  void* mapped = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
  ::close(fd);
  if (mapped == MAP_FAILED) return 0;
  const char* const bytes = static_cast<const char*>(mapped);
  std::vector<double> sums(threads, 0.0);
  const Stopwatch clock;
  std::vector<std::thread> workers;
  for (std::size_t t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      const std::size_t body = size - header_bytes;
      std::size_t begin = header_bytes + body * t / threads;
      std::size_t end = header_bytes + body * (t + 1) / threads;
      double sum = 0;
      if (!csv) {
        begin -= (begin - header_bytes) % sizeof(double);
        end -= (end - header_bytes) % sizeof(double);
        for (std::size_t at = begin; at < end; at += sizeof(double)) {
          double x;
          std::memcpy(&x, bytes + at, sizeof(double));
          sum += x;
        }
      } else {
        const char* p = bytes + begin;
        if (t > 0) {
          while (p < bytes + size && p[-1] != '\n') ++p;
        }
        while (p < bytes + end) {
          const char* line_end = p;
          while (line_end < bytes + size && *line_end != '\n') ++line_end;
          while (p < line_end) {
            double x = 0;
            const auto r = std::from_chars(p, line_end, x);
            sum += x;
            p = r.ptr;
            if (p < line_end) ++p;  // the separator (or a character from_chars refused)
          }
          p = line_end + 1;
        }
      }
      sums[t] = sum;
    });
  }
  for (std::thread& w : workers) w.join();
  const double seconds = clock.seconds();
  ::munmap(mapped, size);
  // The sum is used, so that no compiler drops the loops.
  double total = 0;
  for (double x : sums) total += x;
  if (total == 0.123456789) std::fprintf(stderr, "(the floor's sum is %g)\n", total);
  return seconds;
}

// The bytes before the first data line of a CSV file: its comment lines and its header line.
std::size_t csv_header_bytes(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "r");
  if (f == nullptr) return 0;
  std::size_t bytes = 0;
  char line[4096];
  while (std::fgets(line, sizeof line, f) != nullptr) {
    bytes += std::strlen(line);
    if (line[0] != '#') break;
  }
  std::fclose(f);
  return bytes;
}

enum class PassKind { kZeroLag, kLagged, kLatent, kDefaults, kRefine, kFormed };

// kLagged: the lagged equations at lags 3..42 (40 lags) with the instruments y, y^2, y^3 and x,
// on a file without the velocity; kZeroLag: the zero-lag equations of degree 3; kLatent: the
// filtered oscillator with z latent (kRefine: and its refinement by simulation error, --refine),
// kDefaults the Duffing model, with no options, on a file of y and x; kFormed the Duffing model
// seen through an accelerometer, with no options, on a file of a and x.
int one_pass(const std::string& path, PassKind kind) {
  const bool filtered = kind == PassKind::kLatent || kind == PassKind::kRefine;
  const momentid::Model model =
      filtered ? momentid::parse_model(kFiltered, "filtered_duffing.mom")
      : kind == PassKind::kFormed
          ? momentid::parse_model(kAccelerometer, "duffing_accelerometer.mom")
          : momentid::parse_model(kModel, "duffing.mom");
  momentid::IdentifyOptions options;
  options.refine = kind == PassKind::kRefine;
  if (kind == PassKind::kLagged) {
    options.lags = {{3, 42}};
    options.instruments = {{{1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {0, 0, 1}}};
  } else if (kind == PassKind::kZeroLag) {
    options.degree = 3;
  }
  const Stopwatch clock;
  const momentid::IdentifyResult result =
      momentid::identify(model, momentid::DataSource::file(path), options);
  const double seconds = clock.seconds();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("%.6f %ld %zu %zu\n", seconds, usage.ru_maxrss, result.data.rows,
              result.data.estimates.mean.size());
  return 0;
}

struct Pass {
  double seconds = 0;
  long peak_kib = 0;
  std::size_t rows = 0, moments = 0;
};

const char* pass_flag(PassKind kind) {
  switch (kind) {
    case PassKind::kLagged:
      return "--lagged-pass";
    case PassKind::kLatent:
      return "--latent-pass";
    case PassKind::kDefaults:
      return "--defaults-pass";
    case PassKind::kRefine:
      return "--refine-pass";
    case PassKind::kFormed:
      return "--formed-pass";
    case PassKind::kZeroLag:
      break;
  }
  return "--pass";
}

Pass run_pass(const std::string& self, const std::string& path,
              PassKind kind = PassKind::kZeroLag) {
  std::string command = "'";
  command.append(self).append("' ").append(pass_flag(kind)).append(" '").append(path).append("'");
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

// The faster of two passes.
Pass best_pass(const std::string& self, const std::string& path,
               PassKind kind = PassKind::kZeroLag) {
  const Pass first = run_pass(self, path, kind);
  const Pass second = run_pass(self, path, kind);
  return second.seconds < first.seconds ? second : first;
}

}  // namespace

int main(int argc, char** argv) {
  if (asked_for_help(argc, argv,
                     "usage: bench_identify [rows=10000000] [directory=/tmp] [--no-baseline]"))
    return 0;
  for (const PassKind kind : {PassKind::kZeroLag, PassKind::kLagged, PassKind::kLatent,
                              PassKind::kDefaults, PassKind::kRefine, PassKind::kFormed}) {
    if (argc == 3 && std::string(argv[1]) == pass_flag(kind)) return one_pass(argv[2], kind);
  }
  const std::size_t rows = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 10000000;
  const std::filesystem::path dir = argc > 2 ? argv[2] : "/tmp";
  std::filesystem::create_directories(dir);
  const bool baseline = !(argc > 3 && std::string(argv[3]) == "--no-baseline");
  const momentid::Model model = momentid::parse_model(kModel, "duffing.mom");
  const std::string big = (dir / "bench_identify_big.csv").string();
  const std::string small = (dir / "bench_identify_small.csv").string();
  write_data(model, big, rows);
  write_data(model, small, rows / 10);
  const double megabytes = static_cast<double>(std::filesystem::file_size(big)) / 1e6;

  const Pass small_pass = run_pass(argv[0], small);
  const Pass pass = best_pass(argv[0], big);
  // The same record as a binary file, and the reading floor of each file on the pass's threads.
  const std::string binary = (dir / "bench_identify_big.bin").string();
  write_data(model, binary, rows, {}, momentid::FileFormat::kBinary);
  const Pass binary_pass = best_pass(argv[0], binary);
  const std::size_t threads = std::max(1u, std::thread::hardware_concurrency());
  const auto floor_of = [&](const std::string& path, bool csv, std::size_t header) {
    return std::min(reading_floor(path, csv, header, threads),
                    reading_floor(path, csv, header, threads));
  };
  const double csv_floor = floor_of(big, true, csv_header_bytes(big));
  const auto binary_bytes = static_cast<std::size_t>(std::filesystem::file_size(binary));
  const double binary_floor =
      floor_of(binary, false, binary_bytes - binary_pass.rows * 4 * sizeof(double));
  const double binary_megabytes = static_cast<double>(binary_bytes) / 1e6;
  std::filesystem::remove(binary);
  // The lagged pass on the same record without its velocity column.
  const std::string displacement = (dir / "bench_identify_displacement.csv").string();
  write_data(model, displacement, rows, {"y", "x"});
  const Pass lagged = best_pass(argv[0], displacement, PassKind::kLagged);
  const double displacement_megabytes =
      static_cast<double>(std::filesystem::file_size(displacement)) / 1e6;
  std::filesystem::remove(displacement);
  // A model with a latent state, and the Duffing model, with the defaults on a record of y and x
  // of the filtered oscillator; the reading floor of that file.
  const std::string filtered = (dir / "bench_identify_filtered.csv").string();
  write_data(momentid::parse_model(kFiltered, "filtered_duffing.mom"), filtered, rows, {"y", "x"});
  const Pass latent = best_pass(argv[0], filtered, PassKind::kLatent);
  const Pass defaults = best_pass(argv[0], filtered, PassKind::kDefaults);
  const double filtered_floor = floor_of(filtered, true, csv_header_bytes(filtered));
  std::filesystem::remove(filtered);
  // The refinement by simulation error on 10^5 rows of that record (fewer when fewer are asked
  // for), against identify alone on the same file.
  const std::string short_filtered = (dir / "bench_identify_filtered_short.csv").string();
  write_data(momentid::parse_model(kFiltered, "filtered_duffing.mom"), short_filtered,
             std::min<std::size_t>(rows, 100000), {"y", "x"});
  const Pass refined = best_pass(argv[0], short_filtered, PassKind::kRefine);
  const Pass unrefined = best_pass(argv[0], short_filtered, PassKind::kLatent);
  std::filesystem::remove(short_filtered);
  // The Duffing oscillator under a multisine force (the acceleration needs a smooth force) from
  // its acceleration and force (y formed, the filter's misfit taken out), against the same run's
  // displacement and force (one pass); the reading floor of the acceleration's file.
  const std::string multisine = "multisine:f1=0.05,f2=1,lines=200,rms=20";
  const std::string accelerations = (dir / "bench_identify_accelerations.csv").string();
  const std::string displacements = (dir / "bench_identify_displacements.csv").string();
  write_data(momentid::parse_model(kAccelerometer, "duffing_accelerometer.mom"), accelerations,
             rows, {"a", "x"}, momentid::FileFormat::kCsv, multisine);
  write_data(model, displacements, rows, {"y", "x"}, momentid::FileFormat::kCsv, multisine);
  const Pass formed = best_pass(argv[0], accelerations, PassKind::kFormed);
  const Pass measured = best_pass(argv[0], displacements, PassKind::kDefaults);
  const double accelerations_floor = floor_of(accelerations, true, csv_header_bytes(accelerations));
  std::filesystem::remove(accelerations);
  std::filesystem::remove(displacements);

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

  std::printf(
      "identify's pass over a CSV of the Duffing model (%zu moments in its equations), best of 2\n",
      pass.moments);
  std::printf("  %zu rows, %.0f MB: %.2f s, %.0f MB/s, %.2f M rows/s\n", pass.rows, megabytes,
              pass.seconds, megabytes / pass.seconds, pass.rows / pass.seconds / 1e6);
  std::printf(
      "  reading floor on %zu threads (every field parsed by std::from_chars): %.3f s; the pass "
      "runs at %.0f%% of it\n",
      threads, csv_floor, 100 * csv_floor / pass.seconds);
  std::printf("the same record as a binary file, %.0f MB: %.2f s, %.0f MB/s, %.2f M rows/s\n",
              binary_megabytes, binary_pass.seconds, binary_megabytes / binary_pass.seconds,
              binary_pass.rows / binary_pass.seconds / 1e6);
  std::printf(
      "  reading floor on %zu threads (every double summed): %.3f s; the pass runs at %.0f%% of "
      "it\n",
      threads, binary_floor, 100 * binary_floor / binary_pass.seconds);
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
  std::printf(
      "the lagged pass, lags 3..42 and 4 instruments (%zu moments), on the same record without "
      "v, best of 2\n",
      lagged.moments);
  std::printf("  %zu rows, %.0f MB: %.2f s, %.2f M rows/s; peak memory %ld KiB\n", lagged.rows,
              displacement_megabytes, lagged.seconds, lagged.rows / lagged.seconds / 1e6,
              lagged.peak_kib);
  std::printf("  ratio lagged / zero-lag: %.2f in time, %.2f in peak memory\n",
              lagged.seconds / pass.seconds,
              static_cast<double>(lagged.peak_kib) / static_cast<double>(pass.peak_kib));
  std::printf(
      "a latent state: the Duffing oscillator behind an input filter from y and x (z not "
      "measured), defaults, best of 2\n");
  std::printf(
      "  %zu rows: %.2f s (%zu moments); the Duffing model on the same file: %.2f s (%zu "
      "moments), ratio %.2f\n",
      latent.rows, latent.seconds, latent.moments, defaults.seconds, defaults.moments,
      latent.seconds / defaults.seconds);
  std::printf(
      "  reading floor (every field parsed): %.3f s; the latent model runs at %.0f%% of it\n",
      filtered_floor, 100 * filtered_floor / latent.seconds);
  std::printf(
      "the refinement by simulation error (--refine) of that model, best of 2\n  %zu rows: "
      "identify --refine %.2f s, identify alone %.2f s, ratio %.2f\n",
      refined.rows, refined.seconds, unrefined.seconds, refined.seconds / unrefined.seconds);
  std::printf(
      "a state formed from its acceleration: the Duffing model from a and x (y formed, the "
      "filter's misfit taken out), defaults, best of 2\n");
  std::printf(
      "  %zu rows: %.2f s; from y and x of the same run: %.2f s, ratio %.2f; reading floor of "
      "the a and x file: %.3f s (%.0f%%)\n",
      formed.rows, formed.seconds, measured.seconds, formed.seconds / measured.seconds,
      accelerations_floor, 100 * accelerations_floor / formed.seconds);
  return 0;
}
