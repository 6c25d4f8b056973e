// The channels' means and their standard errors, which tell a sensor offset from the mean a
// finite record has by chance (docs/cli/identify.md, "Warnings").

#include <cmath>

#include "app/identify/steps.hpp"
#include "solve/delta_method.hpp"

namespace momentid {

std::vector<Monomial> first_moments_of(std::size_t channels, std::size_t variables) {
  std::vector<Monomial> out;
  for (std::size_t c = 0; c < channels; ++c) {
    Monomial m(std::max(variables, channels), 0);
    m[c] = 1;
    out.push_back(std::move(m));
  }
  return out;
}

std::vector<ChannelMean> channel_means(const std::vector<std::string>& names,
                                       const MomentEstimates& all,
                                       const std::vector<std::size_t>& index) {
  const MomentEstimates means = moments_at(all, index);
  std::vector<ChannelMean> out;
  if (means.batch_means.size() < 2) return out;
  const LongRunCovariance errors = long_run_covariance(batch_deviations(means));
  for (std::size_t c = 0; c < names.size(); ++c) {
    const auto i = static_cast<Eigen::Index>(c);
    out.push_back({names[c], means.mean[c], std::sqrt(errors.covariance(i, i))});
  }
  return out;
}

}  // namespace momentid
