#pragma once
// The arrays of the Python module: the records handed over from Python, and the series of a
// record that a replay and validate() return, every run's rows one run after the other.

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

// The replay as `simulate --input-file` writes it: t, every state (simulated) and the inputs
// (recorded), run when there are several.
pybind11::dict replay_columns(const Model& model, const Replay& done);

// The series validate compared: t, run (None for one run), every state as simulated, the
// measured states and the inputs as recorded, and whether a row is past its run's skip, so among
// those the fit and the errors are over.
pybind11::dict validate_series(const ValidateResult& result);

}  // namespace momentid::python
