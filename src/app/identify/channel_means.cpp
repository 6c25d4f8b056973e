// The channels' means and their standard errors, which tell a sensor offset from the mean a
// finite record has by chance (docs/cli/identify.md, "Warnings").

#include "app/identify/channel_means.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

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

namespace {

// The variance of state s without its white noise: from its channel, or else, for the rate w of
// a kinematic y' = ratio w, from the channel of y as Var(y(t + dt) - y(t)) / (ratio dt)^2 (the
// lag-1 autocovariance has no white noise in it). Nullopt when neither channel is read.
std::optional<double> state_variance(const Model& model, const DataMoments& data, int s,
                                     double dt) {
  const auto clean = [](const ChannelStatistics& c) {
    return std::max(c.variance - c.noise_variance.value_or(0.0), 0.0);
  };
  if (const ChannelStatistics* c = data.channel(model.states()[static_cast<std::size_t>(s)].name)) {
    return clean(*c);
  }
  const int y = model.integral_of(s);
  if (y < 0) return std::nullopt;
  const ChannelStatistics* c = data.channel(model.states()[static_cast<std::size_t>(y)].name);
  if (!c || c->autocorrelation.empty()) return std::nullopt;
  const double step = model.kinematic(y)->ratio.to_double() * dt;
  return std::max(2 * (clean(*c) - c->autocorrelation[0] * c->variance), 0.0) / (step * step);
}

}  // namespace

void add_end_errors(std::vector<ChannelMean>& means, const Model& model, const DataMoments& data) {
  if (!data.time_step || data.estimates.intervals == 0) return;
  const double duration = static_cast<double>(data.estimates.intervals) * *data.time_step;
  const double runs = static_cast<double>(std::max<std::size_t>(data.runs, 1));
  const auto add = [&](const std::string& rate, double variance, double scale) {
    const auto mean = std::find_if(means.begin(), means.end(),
                                   [&](const ChannelMean& m) { return m.name == rate; });
    if (mean == means.end()) return;
    const double ends = 2 * runs * variance / (scale * scale);
    mean->std_error = std::sqrt(mean->std_error * mean->std_error + ends);
  };
  for (std::size_t s = 0; s < model.states().size(); ++s) {
    const std::optional<Kinematic> k = model.kinematic(static_cast<int>(s));
    if (!k) continue;
    const ChannelStatistics* integral = data.channel(model.states()[s].name);
    if (!integral) continue;
    add(model.variables()[static_cast<std::size_t>(k->state)].name, integral->variance,
        k->ratio.to_double() * duration);
  }
  // A column of a state's derivative (a = v'), read as a channel of its own.
  for (const MeasuredDerivative& d : model.measured_derivatives()) {
    if (const std::optional<double> variance =
            state_variance(model, data, d.state, *data.time_step)) {
      add(d.name, *variance, duration);
    }
  }
}

}  // namespace momentid
