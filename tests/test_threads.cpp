// Calls from several threads at once (momentid/algebra_lock.hpp): each thread parses its own
// models and identifies, checks, validates and selects terms on records that all threads share;
// every result must equal the one a single thread gets. An executable of its own, so that CI
// builds it alone under ThreadSanitizer.

#include <doctest/doctest.h>

#include <exception>
#include <string>
#include <thread>
#include <vector>

#include "momentid/momentid.hpp"
#include "test_support.hpp"

namespace {

using momentid::Model;

// Every channel of a simulation, column by column.
struct Columns : momentid::SampleSink {
  std::vector<std::vector<double>> values;
  explicit Columns(std::size_t channels) : values(channels) {}
  void sample(double, const double* row, std::size_t) override {
    for (std::size_t c = 0; c < values.size(); ++c) values[c].push_back(row[c]);
  }
};

constexpr std::size_t kSamples = 20000;

// The Duffing model under its held moving-average input: without noise, every channel (what
// simulate writes, the input held over each sample), in memory and in a CSV file that one source
// (whose copies share the stamps of the file) reads for every thread; with noise on y, y and x
// alone.
struct Records {
  Columns clean{3}, noisy{3};
  momentid::testing::Directory directory{"momentid_threads"};
  momentid::DataSource file = momentid::DataSource::file(directory / "record.csv");
  Records() {
    const Model model = momentid::testing::model_file("duffing.mom");
    momentid::SimulationOptions options = momentid::testing::options_for(model, kSamples, 7);
    momentid::simulate(model, options, clean);
    momentid::simulate_to_file(model, options, directory / "record.csv",
                               momentid::DataWriter::Format::kCsv);
    options.noise = {{"y", 0.05}};
    momentid::simulate(model, options, noisy);
  }
  // The arrays are shared: every source reads them in place.
  momentid::DataSource held(bool with_model_name) const {
    momentid::MemoryData data;
    data.rows = kSamples;
    data.columns = {{"y", clean.values[0].data()},
                    {"v", clean.values[1].data()},
                    {"x", clean.values[2].data()}};
    if (with_model_name) data.metadata.add_line({{"model", "duffing"}});
    data.metadata.add_line({{"dt", "0.01"}, {"input-hold", "zoh"}});
    return momentid::DataSource::memory(std::move(data));
  }
  momentid::DataSource displacement() const {
    momentid::MemoryData data;
    data.rows = kSamples;
    data.columns = {{"y", noisy.values[0].data()}, {"x", noisy.values[2].data()}};
    data.metadata.add_line({{"dt", "0.01"}, {"input-hold", "zoh"}});
    return momentid::DataSource::memory(std::move(data));
  }
};

// What one thread computes, as text: zero-lag identify on the held record in memory, identify
// with the defaults on its file, lagged identify on the noisy one, check, validate, and term
// selection from the polynomial library. Two passes read on two threads of their own.
std::vector<std::string> results(const Records& records) {
  const Model model = momentid::testing::model_file("duffing.mom");
  const Model library =
      momentid::parse_model_file(std::string(MOMENTID_SOURCE_DIR) + "/examples/select/library.mom");
  momentid::IdentifyOptions zero_lag{.degree = 3};
  zero_lag.method = momentid::Method::kZeroLag;
  zero_lag.record.control.threads = 2;
  momentid::IdentifyOptions lagged{.method = momentid::Method::kLagged};
  momentid::CheckOptions check;
  check.record.control.threads = 2;
  return {
      momentid::format_json(momentid::identify(model, records.held(true), zero_lag)),
      momentid::format_json(momentid::identify(model, records.file)),
      momentid::format_json(momentid::identify(model, records.displacement(), lagged)),
      momentid::format_text(momentid::check(records.held(false), &model, check)),
      momentid::format_json(momentid::validate(model, records.held(true), {})),
      momentid::format_json(momentid::select_terms(library, records.held(false))),
  };
}

// Runs `results` on `threads` threads at once, `rounds` times, and compares each with `serial`.
// ThreadSanitizer sees a race between any two threads whose accesses no lock orders, whether or
// not they overlap in time: four threads on two cores, once, are enough.
void compare_threads(const Records& records, const std::vector<std::string>& serial,
                     std::size_t threads, int rounds) {
  for (int round = 0; round < rounds; ++round) {
    std::vector<std::vector<std::string>> got(threads);
    std::vector<std::thread> pool;
    for (std::size_t t = 0; t < threads; ++t) {
      pool.emplace_back([&, t] {
        try {
          got[t] = results(records);
        } catch (const std::exception& e) {
          got[t].assign(serial.size(), std::string("threw: ") + e.what());
        }
      });
    }
    for (std::thread& thread : pool) thread.join();
    for (std::size_t t = 0; t < threads; ++t) {
      for (std::size_t r = 0; r < serial.size(); ++r) {
        INFO("round ", round, ", thread ", t, " of ", threads, ", result ", r);
        CHECK(got[t][r] == serial[r]);
      }
    }
  }
}

}  // namespace

TEST_SUITE("threads") {
  TEST_CASE(
      "identify, check, validate and select on several threads give the serial results exactly") {
    const Records records;
    const std::vector<std::string> serial = results(records);
    compare_threads(records, serial, 4, 1);
  }
}
