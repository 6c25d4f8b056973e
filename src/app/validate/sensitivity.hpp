#pragma once
// Whether the model's trajectory under the record's input can be reproduced at all: how fast a
// small perturbation of its initial state grows (Sensitivity).

#include "momentid/simulate.hpp"
#include "momentid/validate.hpp"

namespace momentid {

// Simulates every run again from its initial state perturbed by Sensitivity::kPerturbation of
// each state's spread (in the replay) and measures the separation; the run where it grew most.
// A perturbed simulation that blows up counts as sensitive.
Sensitivity measure_sensitivity(const Model& model, const RecordSimulator& simulator,
                                const Replay& replay);

}  // namespace momentid
