#pragma once
// Each result as one JSON value (docs/json.md): the command line prints its text (format_json,
// declared beside each result), the Python module converts it into Python objects, and a C++
// program may read it as it is, without parsing text. The value is what the text reads back as:
// a number that is not finite is null in both.
//
// Example:
//   const nlohmann::ordered_json value = json_value(identify(model, source));
//   double k = value["parameters"]["k"]["estimate"].get<double>();

#include <nlohmann/json.hpp>

namespace momentid {

struct CheckResult;
struct IdentifyResult;
struct LaggedSystem;
struct MomentSystem;
struct RefineResult;
struct SelectResult;
struct ValidateResult;

// docs/json.md, "derive": the zero-lag moment equations.
nlohmann::ordered_json json_value(const MomentSystem& system);
// The lagged moment equations, as `derive --lags` prints them.
nlohmann::ordered_json json_value(const LaggedSystem& system);
// docs/json.md, "identify".
nlohmann::ordered_json json_value(const IdentifyResult& result);
// docs/json.md, "select".
nlohmann::ordered_json json_value(const SelectResult& result);
// docs/json.md, "check".
nlohmann::ordered_json json_value(const CheckResult& result);
// docs/json.md, "refine".
nlohmann::ordered_json json_value(const RefineResult& result);
// docs/json.md, "validate".
nlohmann::ordered_json json_value(const ValidateResult& result);

}  // namespace momentid
