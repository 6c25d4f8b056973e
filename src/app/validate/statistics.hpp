#pragma once
// The statistical validation of a model whose trajectory cannot be reproduced: the record's
// power spectral densities, amplitude quantiles and level up-crossing rates against bands from
// simulations driven by the same input from other initial states (StatisticalValidation).

#include <cstddef>
#include <vector>

#include "momentid/simulate.hpp"
#include "momentid/validate.hpp"

namespace momentid {

// Compares the outputs `outputs` (fit.hpp: model states, then measured derivatives, those the
// record has, in order) of the replayed record with StatisticalValidation::kRuns simulations;
// not compared (with the reason) when the shortest run has fewer than kMinSegment *
// kMinSegments rows. The prediction checks need every state among them.
StatisticalValidation compare_statistics(const Model& model, const RecordSimulator& simulator,
                                         const Replay& replay,
                                         const std::vector<std::size_t>& outputs);

}  // namespace momentid
