#include "solve/identities.hpp"

#include <cmath>
#include <map>

#include "solve/delta_method.hpp"
#include "solve/long_run.hpp"
#include "solve/numbers.hpp"
#include "solve/rows.hpp"

namespace momentid {

using Eigen::Index;
using Eigen::VectorXd;

std::vector<IdentityCheck> identity_checks(const MomentSystem& system,
                                           const std::vector<Monomial>& moments,
                                           const MomentEstimates& estimates,
                                           const Eigen::MatrixXd& deviations) {
  const Model& model = *system.model;
  const std::map<Monomial, std::size_t> index = positions(moments);
  std::vector<IdentityCheck> out;
  for (const DataIdentity& id : system.identities) {
    // Weights over the moments: +1 for E[m], minus the value's weights; E[1] is a constant.
    const std::optional<MomentRows::Entry> value = entry_of(id.value, index);
    if (index.count(id.moment) == 0 || !value) continue;
    VectorXd weights = VectorXd::Zero(deviations.cols());
    weights(static_cast<Index>(index.at(id.moment))) += 1.0;
    for (const auto& [k, w] : value->moments) weights(static_cast<Index>(k)) -= w;
    IdentityCheck check;
    check.identity = format_moment(model, id.moment) + " = " + format_combination(model, id.value);
    check.violation = -value->constant;
    for (Index i = 0; i < weights.size(); ++i) {
      check.violation += weights(i) * estimates.mean[static_cast<std::size_t>(i)];
    }
    const double variance = long_run_covariance(deviations * weights).covariance(0, 0);
    check.z = variance > 0 ? check.violation / std::sqrt(variance) : kNaN;
    out.push_back(check);
  }
  return out;
}

std::vector<IdentityCheck> check_identities(const MomentSystem& system,
                                            const std::vector<Monomial>& moments,
                                            const MomentEstimates& estimates) {
  // The given moments in the order the solver reads them, so that the checks are the same to
  // the last bit whatever the order they are given in.
  const std::map<Monomial, std::size_t> given = positions(moments);
  std::vector<Monomial> available;
  for (const Monomial& m : moments_to_estimate(system)) {
    if (given.count(m) != 0) available.push_back(m);
  }
  const MomentEstimates own =
      estimates_of(available, moments, estimates, *system.model, "check_identities");
  return identity_checks(system, available, own, batch_deviations(own));
}

}  // namespace momentid
