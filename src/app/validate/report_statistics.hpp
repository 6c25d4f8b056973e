#pragma once
// The parts of validate's reports about sensitivity, the response's statistics and the verdict.

#include <nlohmann/json.hpp>
#include <string>

#include "momentid/validate.hpp"

namespace momentid {

// One line: how fast a perturbation grew or shrank, and what that means for the trajectory.
std::string sensitivity_text(const ValidateResult& result);
// The statistics block (empty when the statistics were not compared), then the verdict line.
std::string statistics_text(const ValidateResult& result);
// Adds the JSON members "sensitive", "consistent", "verdict", "sensitivity" and "statistics" to
// `out`.
void statistics_json(nlohmann::ordered_json& out, const ValidateResult& result);

}  // namespace momentid
