#pragma once

// The zero-lag check of a lagged estimate (IdentifyResult::Lagged::ZeroLagCheck).

#include <optional>
#include <string>
#include <vector>

#include "momentid/derive.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {

// The zero-lag check's highest degree and what the lagged pass reads for it.
struct ZeroLagCheckPlan {
  int degree = 0;
  std::optional<MomentSystem> system;  // the zero-lag equations at `degree`
  std::vector<Monomial> moments;       // over the model's variables, with their noise corrections'
  std::string unavailable;             // why no degree fits the check, when none does
};

// The plan of the zero-lag check (IdentifyResult::Lagged::ZeroLagCheck) when the defaults take
// the lagged equations for a record that shows every state and input (`measured`, per model
// variable) in its own column (with `unavailable` set when even degree 1 exceeds the check's
// budget of equations); nullopt otherwise.
std::optional<ZeroLagCheckPlan> plan_zero_lag_check(const Model& model,
                                                    const IdentifyOptions& options,
                                                    const std::vector<bool>& measured);

// The check into result.lagged->zero_lag_check, after the lagged estimate: `moments` are the
// estimates of plan.moments from the same pass (its batches), `channel` the pass's channel per
// model variable. At the highest degree up to plan.degree whose equations keep
// kBatchesPerEquation batches each; `fixed` as fixed_values gives it.
void check_with_zero_lag(IdentifyResult& result, const ZeroLagCheckPlan& plan,
                         const MomentEstimates& moments, const std::vector<int>& channel,
                         const std::vector<std::optional<double>>& fixed);

}  // namespace momentid
