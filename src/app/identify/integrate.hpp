#pragma once

// States formed from the columns of their derivatives (IdentifyOptions::integrate).

#include <vector>

#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {

// For IdentifyOptions::integrate: the column each named state is formed from (the record must
// show it only as the integral of one) and the filter's corner, given or chosen from the band of
// the record's first input with a column (else of the column integrated); marks the formed
// states present. Throws UsageError naming integrate, DataError for a record without a sample
// interval or too short for its band.
IdentifyResult::Integration plan_integration(const Model& model, const DataSource& source,
                                             const IdentifyOptions& options,
                                             std::vector<bool>& present);

}  // namespace momentid
