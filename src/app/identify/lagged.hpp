#pragma once

// The lagged path of identify() (docs/measured-data.md), and the rows of its equations for
// another command (term selection) to weigh.

#include <vector>

#include "momentid/estimate.hpp"
#include "momentid/identify.hpp"
#include "momentid/lagged.hpp"

namespace momentid {

// The lagged identification into `result` (whose model is set): the equations for the lags
// asked for, or for a window the data's correlation times call for, one pass (two when the
// first shows them much longer than its window), the noise on each state channel, the solution.
// `measured`: per model variable, whether the data have its column.
void identify_lagged(IdentifyResult& result, const DataSource& source,
                     const IdentifyOptions& options, const std::vector<bool>& measured);

// The equations of `system` (the result's own lagged system, or one derived with its
// instruments at fewer lags) as rows over the moments of the result's pass
// (result.lagged->moments), with the result's noise and stencils.
MomentRows lagged_rows_of(const IdentifyResult& result, const LaggedSystem& system);

}  // namespace momentid
