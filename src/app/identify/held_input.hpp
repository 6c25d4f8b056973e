#pragma once

// The correction of the zero-lag moments for an input held over each sample.

#include <vector>

#include "momentid/derive.hpp"
#include "momentid/estimate.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {

// The moments the E[g''] of `held` are made of.
std::vector<Monomial> second_derivative_moments(const HeldInputCorrections& held);

// Data whose input is held over each sample: replaces the estimate of `result` by the one from
// moments corrected for the kinks of the held input, E[g] = E_dt[g] - dt^2/12 E[g''] (derive.hpp,
// held_input_corrections), with the weights of E[g''] at the parameters of the previous
// estimate, twice (the second pass changes the estimates by O(dt^4)). `all` holds the moments
// `moments` in that order, the system's first.
void correct_for_held_input(IdentifyResult& result, const HeldInputCorrections& held,
                            const std::vector<Monomial>& moments, const MomentEstimates& all,
                            const SolveOptions& solve_options);

}  // namespace momentid
