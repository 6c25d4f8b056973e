#pragma once
// The identified model's response to the recorded inputs, for the offset check
// (IdentifyResult::response_means).

#include "momentid/identify.hpp"
#include "momentid/reader.hpp"

namespace momentid {

// Whether a symmetric model's states may carry an offset: the offset check names a state's mean
// at the weaker level it uses beside a rejecting J test, or the J test rejects the model (a
// periodic force's own mean response may hide an offset from a check against zero).
bool offset_in_doubt(const IdentifyResult& result);

// Sets result.response_means when offset_in_doubt: the record's first rows read as validate
// reads them (less the means the pass removed), the model at its estimates simulated through
// its inputs. Leaves them empty where the response cannot be had, saying why in
// result.response_failure (an input without a column, a simulation that blows up or does not
// follow the record); and where the estimate is not usable, silently.
void simulate_response_means(IdentifyResult& result, const DataSource& source,
                             const IdentifyOptions& options);

}  // namespace momentid
