#pragma once
// Parameter values by name, as a user gives them to simulate and validate: no positions, no
// symbolic numbers.

#include <map>
#include <string>

namespace momentid {

// A parameter's value: a number, or a decimal exactly as written (`--set k=0.1`, a Python
// float's repr). A decimal stays exact where the model is compiled (1/10, not the double nearest
// to it), so that its coefficients are rounded once, after they are combined; a double cannot
// carry a decimal of more than 17 significant digits, which is why the text is kept.
//
// Example:
//   ParameterValues values = {{"c", 0.55}, {"k", ParameterValue::exact("4.1")}};
struct ParameterValue {
  ParameterValue(double number = 0) : value(number) {}  // NOLINT: a number is a value
  // `text` must be a decimal ([+-] digits [. digits] [e [+-] digits]); `value` is its nearest
  // double.
  static ParameterValue exact(std::string text);

  double value = 0;
  std::string decimal;  // empty: `value` is the value
};

// Values by parameter name. Where a model is simulated, a parameter absent from the map takes
// its nominal value (`param k = 4` in the model file).
using ParameterValues = std::map<std::string, ParameterValue>;

}  // namespace momentid
