#pragma once

// The sampling bias of the zero-lag estimate (IdentifyOptions::extrapolate).

#include <optional>
#include <vector>

#include "momentid/data_pass.hpp"
#include "momentid/identify.hpp"

namespace momentid {

// IdentifyOptions::extrapolate, after the zero-lag estimate `result` (whose first-order errors
// over the batches are result.estimate.error_batches): the same estimate from every other sample
// (both halves of each run, in the same batches), the difference's error from the long-run
// covariance of the difference of the two error series, and Richardson's extrapolation when a
// difference exceeds its error.
void estimate_sampling_bias(IdentifyResult& result, const DataSource& source,
                            DataOptions data_options,
                            const std::vector<std::optional<double>>& fixed);

}  // namespace momentid
