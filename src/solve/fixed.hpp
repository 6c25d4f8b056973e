#pragma once

// Parameters given rather than estimated (SolveOptions::fixed): their terms move to the
// right-hand side, the rest is solved, and the result is spread back over all the parameters.

#include <optional>
#include <string>
#include <vector>

#include "momentid/estimate.hpp"

namespace momentid {

// `rows` with the fixed parameters' columns moved to the right-hand side: b - a_p v_p. `fixed`
// has one entry per column.
MomentRows without_fixed(const MomentRows& rows, const std::vector<std::optional<double>>& fixed);

// The estimate of the free parameters spread back over all of them, named `names`: the fixed
// ones with their values, no error, no correlation and zero columns in the error batches.
Estimate with_fixed(Estimate free, const std::vector<std::string>& names,
                    const std::vector<std::optional<double>>& fixed);

}  // namespace momentid
