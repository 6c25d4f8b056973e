#pragma once
// A result's JSON value (momentid/json.hpp) as the Python objects json.loads would make of its
// text: dict (in the value's order), list, float, int, str, bool and None.

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>

namespace momentid::python {

pybind11::object to_python(const nlohmann::ordered_json& value);

}  // namespace momentid::python
