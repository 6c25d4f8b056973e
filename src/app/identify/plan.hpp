#pragma once

// The choices identify() makes before it reads the record: which equations, whether they are
// optimally weighted, which parameters are fixed.

#include <optional>
#include <string>
#include <vector>

#include "app/variables.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {

// Four batches per equation keep the optimal weighting's batch covariance well conditioned.
inline constexpr std::size_t kBatchesPerEquation = 4;

enum class EquationKind { kZeroLag, kLagged };

// Which equations identify takes for a record, and why (IdentifyResult::why).
struct EquationChoice {
  EquationKind kind;
  std::string why;
};

// IdentifyOptions::method, or for kAuto: the lagged equations when lags or instruments are given,
// or the record lacks a state they can read as a derivative, or it is measured (not known to be
// noise-free) and gives a sample interval; the zero-lag ones for the rest, and for zero-lag
// options (multipliers, a degree, extrapolate) on records with every state. Models with abs and
// sign terms alike: a record that lacks the column of such a term's argument, while showing
// every state, gets the lagged equations, which refuse the term by name.
// Whether the channels flagged in `measured` (per channel) leave some state latent, shown
// neither as a column nor through a kinematic equation or a derivative column
// (docs/latent-states.md), while they show another state and hold every input: a record whose
// columns miss the model altogether gets the message naming the missing column instead.
bool latent_model(const Model& model, const std::vector<bool>& measured);

EquationChoice choose_equations(const Model& model, const RecordSurvey& record,
                                const IdentifyOptions& options);

// Whether the main estimate is the optimally weighted one (IdentifyOptions::weighting) for a
// system of `equations` equations in parameters of which `fixed` (fixed_values) fixes some: by
// default whenever the equations outnumber the free parameters, so that the J test can check the
// model (not with IdentifyOptions::extrapolate, whose two estimates need one weighting).
bool optimal_weighting(const IdentifyOptions& options,
                       const std::vector<std::optional<double>>& fixed, std::size_t equations);

// The parameters fixed by IdentifyOptions::fixed or in the model file (the option's value wins),
// as SolveOptions::fixed wants them: per parameter, in declaration order.
std::vector<std::optional<double>> fixed_values(const Model& model,
                                                const std::map<std::string, double>& fixed);

}  // namespace momentid
