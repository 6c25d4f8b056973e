// The channels' means and their standard errors, which tell a sensor offset from the mean a
// finite record has by chance (docs/cli/identify.md, "Warnings").

#include "app/identify/channel_means.hpp"

#include <algorithm>
#include <cmath>

#include "app/identify/moment_lists.hpp"
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

void add_end_errors(std::vector<ChannelMean>& means, const Model& model, const DataMoments& data) {
  if (!data.time_step || data.estimates.intervals == 0) return;
  const double duration = static_cast<double>(data.estimates.intervals) * *data.time_step;
  const double runs = static_cast<double>(std::max<std::size_t>(data.runs, 1));
  for (std::size_t s = 0; s < model.states().size(); ++s) {
    const std::optional<Kinematic> k = model.kinematic(static_cast<int>(s));
    if (!k) continue;
    const std::string& integral = model.states()[s].name;
    const std::string& rate = model.variables()[static_cast<std::size_t>(k->state)].name;
    const auto statistics =
        std::find_if(data.channels.begin(), data.channels.end(),
                     [&](const ChannelStatistics& c) { return c.name == integral; });
    const auto mean = std::find_if(means.begin(), means.end(),
                                   [&](const ChannelMean& m) { return m.name == rate; });
    if (statistics == data.channels.end() || mean == means.end()) continue;
    const double scale = k->ratio.to_double() * duration;
    const double ends = 2 * runs * statistics->variance / (scale * scale);
    mean->std_error = std::sqrt(mean->std_error * mean->std_error + ends);
  }
}

}  // namespace momentid
