#pragma once
// The arrays of the Python module: the records handed over from Python, the samples simulate()
// writes into, and the series of a record that a replay and validate() return, every run's rows
// one run after the other.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "momentid/momentid.hpp"

namespace momentid::python {

// A record handed over from Python: a file path, or columns of numbers that are read in place.
// The arrays (float64, one dimension, any stride that is a whole number of values) are kept
// alive by the caller for as long as the source is used.
DataSource data_source(const pybind11::object& data, const std::string& name,
                       const std::map<std::string, std::string>& metadata);

// Writes the samples into arrays, one per channel, run after run.
class ArraySink : public SampleSink {
 public:
  ArraySink(std::vector<double*> columns, std::vector<std::size_t> channels, double* time,
            double* run, std::size_t samples)
      : columns_(std::move(columns)),
        channels_(std::move(channels)),
        time_(time),
        run_(run),
        samples_(samples) {}
  void sample(double t, const double* values, std::size_t run) override {
    if (run != run_index_) {
      run_index_ = run;
      row_in_run_ = 0;
    }
    const std::size_t row = run * samples_ + row_in_run_++;
    time_[row] = t;
    if (run_ != nullptr) run_[row] = static_cast<double>(run + 1);
    for (std::size_t c = 0; c < channels_.size(); ++c) columns_[c][row] = values[channels_[c]];
  }

 private:
  std::vector<double*> columns_;
  std::vector<std::size_t> channels_;
  double *time_, *run_;
  std::size_t samples_, run_index_ = 0, row_in_run_ = 0;
};

// The replay as `simulate --input-file` writes it: t, every state (simulated) and the inputs
// (recorded), run when there are several.
pybind11::dict replay_columns(const Model& model, const Replay& done);

// The series validate compared: t, run (None for one run), every state as simulated, the
// measured states and the inputs as recorded, and whether a row is past its run's skip, so among
// those the fit and the errors are over.
pybind11::dict validate_series(const ValidateResult& result);

}  // namespace momentid::python
