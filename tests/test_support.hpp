#pragma once
// Helpers shared by the unit tests.

#include <doctest/doctest.h>
#include <unistd.h>

#include <exception>
#include <filesystem>
#include <string>
#include <typeinfo>
#include <vector>

#include "momentid/lagged.hpp"
#include "momentid/model.hpp"
#include "momentid/simulate.hpp"

namespace momentid::testing {

// Keeps every simulated sample: rows[n] = t, states, inputs, run (from 0).
struct Recorder : SampleSink {
  std::vector<std::vector<double>> rows;
  std::size_t width = 0;
  explicit Recorder(std::size_t values) : width(values) {}
  void sample(double t, const double* values, std::size_t run) override {
    std::vector<double> row{t};
    row.insert(row.end(), values, values + width);
    row.push_back(static_cast<double>(run));
    rows.push_back(std::move(row));
  }
  std::vector<double> column(std::size_t c) const {
    std::vector<double> out;
    for (const auto& row : rows) out.push_back(row[c]);
    return out;
  }
};

// A temporary directory of its own (`prefix`, the process and a count), removed at the end.
struct Directory {
  explicit Directory(const std::string& prefix)
      : path(std::filesystem::temp_directory_path() /
             (prefix + "_" + std::to_string(::getpid()) + "_" + std::to_string(count++))) {
    std::filesystem::create_directories(path);
  }
  ~Directory() { std::filesystem::remove_all(path); }
  Directory(const Directory&) = delete;
  Directory& operator=(const Directory&) = delete;
  std::string operator/(const std::string& name) const { return (path / name).string(); }
  std::filesystem::path path;
  static inline int count = 0;
};

// Nominal parameters, the default input process for every input, 2000 steps of burn-in.
inline SimulationOptions options_for(const Model& model, std::size_t samples, std::uint64_t seed) {
  SimulationOptions options;
  options.inputs.assign(model.inputs().size(), InputSpec{});
  options.samples = samples;
  options.burn_in = 2000;
  options.seed = seed;
  return options;
}

// The lagged equation `i` of `system` as derive prints it: everything after its source column.
inline std::string lagged_equation_text(const LaggedSystem& system, std::size_t i) {
  const std::string text = format_text(system);
  std::size_t at = 0;
  for (std::size_t line = 0; line < 3 + i; ++line) at = text.find('\n', at) + 1;
  const std::string line = text.substr(at, text.find('\n', at) - at);
  const std::size_t source = line.find("(t-s)");
  REQUIRE(source != std::string::npos);
  return line.substr(line.find_first_not_of(' ', source + 5));
}

// A model from the project's models/ folder.
inline Model model_file(const std::string& name) {
  return parse_model_file(std::string(MOMENTID_SOURCE_DIR) + "/models/" + name);
}

// Runs `action` and returns the exception it throws, which must be exactly of type E. Fails the
// test case when `action` throws nothing, or something else.
template <class E, class Action>
E error_from(Action&& action) {
  try {
    action();
  } catch (const E& e) {
    if (typeid(e) != typeid(E)) FAIL("threw " << typeid(e).name() << ": " << e.what());
    return e;
  } catch (const std::exception& e) {
    FAIL("threw " << typeid(e).name() << " instead: " << e.what());
  } catch (...) {
    FAIL("threw something that is not a std::exception");
  }
  FAIL("threw nothing");
  throw;  // not reached: FAIL throws
}

}  // namespace momentid::testing
