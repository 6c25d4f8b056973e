#pragma once

#include <Eigen/Dense>
#include <vector>

#include "momentid/estimate.hpp"

namespace momentid {

// check_identities on estimates of `moments` in that order, with their batch series
// (batch_deviations) at hand.
std::vector<IdentityCheck> identity_checks(const MomentSystem& system,
                                           const std::vector<Monomial>& moments,
                                           const MomentEstimates& estimates,
                                           const Eigen::MatrixXd& deviations);

}  // namespace momentid
