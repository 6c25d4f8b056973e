#pragma once

// Models with latent states (docs/latent-states.md): the equations with the latent states
// eliminated are estimated by the lagged pass, and the parameters found from their coefficients
// by minimum distance.

#include <vector>

#include "momentid/identify.hpp"

namespace momentid {

// Identifies result.model, which has latent states, from `source`: eliminates them
// (eliminate_latent), estimates the coefficients of the equations without them with the lagged
// equations (identify_lagged on coefficient_model), and maps the coefficients to the parameters
// (IdentifyResult::Latent). Throws ModelError before the pass when the coefficients leave a
// parameter undetermined, naming what to fix.
void identify_latent(IdentifyResult& result, const DataSource& source,
                     const IdentifyOptions& options, const std::vector<bool>& measured);

}  // namespace momentid
