#pragma once
// The simulation of a model through a record's inputs: how long it takes to forget its initial
// state, for the rows that validate leaves out.

#include <cstddef>
#include <utility>
#include <vector>

#include "momentid/simulate.hpp"
#include "momentid/validate.hpp"

namespace momentid {

// Simulates the model through the inputs of a record already read (replay() reads it first).
Replay replay_record(const Model& model, Record record, const ReplayOptions& options);

// The row from which the simulation of a run has forgotten its initial state (see
// ValidateResult::skip), searched over the first half of the run, and the size of the
// perturbation left at the end of the search, relative to its start.
std::pair<std::size_t, double> forgetting_row(const RecordSimulator& simulator,
                                              const std::vector<std::vector<double>>& inputs,
                                              const std::vector<double>& initial,
                                              const std::vector<std::vector<double>>& simulated,
                                              double start, std::size_t label);

}  // namespace momentid
