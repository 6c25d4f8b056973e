// What makes an identification doubtful, and every warning about it (docs/cli/identify.md,
// "Warnings").

#include <algorithm>
#include <cmath>

#include "common/number.hpp"
#include "momentid/identify.hpp"

namespace momentid {
namespace {

// Sensor noise above this fraction of a state's standard deviation is reported. Below it the
// estimate cannot tell noise from the roughness of a state whose derivative holds a held input.
constexpr double kNoiseWarning = 0.02;

// What makes a result doubtful, and what draws a warning (docs/cli/identify.md, "Warnings").
constexpr double kIdentityZ = 4;      // |z| of a stationarity identity's violation
constexpr double kJRejection = 0.01;  // p-value of the J test
constexpr double kOffset = 0.2;       // |mean| / standard deviation of a channel
constexpr double kWeakRelativeError = 0.1;
constexpr double kStrongCorrelation = 0.95;

// Whether every term of every equation has an odd degree, counting a derivative as a factor:
// then the model is unchanged when every state and input changes sign, and zero-mean inputs
// give zero-mean states.
bool symmetric(const Model& model) {
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      int degree = t.derivative >= 0 ? 1 : 0;
      for (int e : t.monomial) degree += e;
      if (degree % 2 == 0) return false;
    }
  }
  return true;
}

}  // namespace

std::vector<std::string> doubts(const IdentifyResult& r) {
  std::vector<std::string> out;
  const Estimate& e = r.estimate;
  if (e.j_pvalue && *e.j_pvalue < kJRejection) {  // the J test comes with the optimal weighting
    out.push_back("the J test rejects the model (p = " + number(*e.j_pvalue, "%.2g") +
                  "): its moment equations disagree with each other more than their errors "
                  "allow. A term may be missing, a noise or an offset not modelled, or the "
                  "record too coarsely sampled: check the estimates with 'momentid validate' "
                  "before using them");
  }
  for (const IdentityCheck& c : e.identities) {
    if (!(std::abs(c.z) > kIdentityZ)) continue;
    out.push_back("the stationarity identity " + c.identity +
                  " is violated (z = " + number(c.z, "%.3g") +
                  "): the record is not stationary (a drift, a start-up transient, runs joined "
                  "end to end), or its columns are not what the model's kinematic equations say "
                  "(v is not y', or the channels are shifted in time)");
  }
  if (symmetric(*r.model)) {
    const auto offset = [](const ChannelStatistics& c) {
      return c.variance > 0 && std::abs(c.mean) > kOffset * std::sqrt(c.variance);
    };
    const auto& channels = r.data.channels;
    const bool inputs_centred = std::none_of(
        channels.begin(), channels.end(), [&](const auto& c) { return c.is_input && offset(c); });
    for (const ChannelStatistics& c : channels) {
      if (c.is_input || !inputs_centred || !offset(c)) continue;
      out.push_back("'" + c.name + "' has the mean " + number(c.mean, "%.3g") + ", " +
                    number(std::abs(c.mean) / std::sqrt(c.variance), "%.2g") +
                    " of its standard deviation, but model " + r.model->name() +
                    " is symmetric (every term odd) and its inputs have no mean, so its states "
                    "have none: a sensor offset? It biases the estimates; if it is one, remove "
                    "it with --center " +
                    c.name);
    }
  }
  return out;
}

Status status(const IdentifyResult& r) {
  if (r.estimate.status != Status::kOk) return r.estimate.status;
  return doubts(r).empty() ? Status::kOk : Status::kDoubtful;
}

std::vector<std::string> warnings(const IdentifyResult& r) {
  std::vector<std::string> w;
  if (r.estimate.status != Status::kOk) w.push_back(r.estimate.message);
  const std::vector<std::string> doubt = doubts(r);
  w.insert(w.end(), doubt.begin(), doubt.end());
  // The optimal weighting that was asked for and could not be made: before the rest.
  for (const std::string& s : r.estimate.warnings) {
    if (s.rfind("no optimally weighted estimate", 0) == 0) w.push_back(s);
  }
  const std::vector<ParameterEstimate>& parameters = r.parameters();
  for (const ParameterEstimate& p : parameters) {
    if (!p.identifiable || !(std::abs(p.std_error) > kWeakRelativeError * std::abs(p.estimate))) {
      continue;
    }
    w.push_back("'" + p.name + "' is weakly determined: its standard error is " +
                number(100 * p.std_error / std::abs(p.estimate), "%.3g") +
                "% of its value. Excite the system more, add multipliers (--degree) or fix "
                "parameters you know");
  }
  const auto& correlation = r.estimate.main().correlation;
  for (std::size_t i = 0; i < correlation.size(); ++i) {
    for (std::size_t j = i + 1; j < correlation.size(); ++j) {
      if (!(std::abs(correlation[i][j]) > kStrongCorrelation)) continue;
      w.push_back("the estimates of '" + parameters[i].name + "' and '" + parameters[j].name +
                  "' are strongly correlated (" + number(correlation[i][j], "%.3f") +
                  "): the data determine a combination of them better than each");
    }
  }
  std::vector<std::string> rest = data_warnings(r.data);
  for (const ChannelStatistics& c : r.data.channels) {
    const std::optional<double> fraction = c.noise_fraction();
    if (c.is_input || !fraction || *fraction < kNoiseWarning) continue;
    rest.push_back("'" + c.name + "' carries white noise of about " +
                   number(100 * *fraction, "%.2g") +
                   "% of its standard deviation (the excess of its autocorrelation at lag 0): " +
                   (r.lagged ? "the lagged equations correct its powers, but the estimates are "
                               "less certain and may still be biased"
                             : "it biases the zero-lag estimates (the lagged equations, --lags, "
                               "correct for it in part)"));
  }
  if (r.lagged) {
    for (const auto& [name, tau] : r.lagged->correlation_lags) {
      if (tau > 0) continue;
      rest.push_back("'" + name + "' stays correlated across lags " +
                     std::to_string(r.lagged->system.first_lag) + ".." +
                     std::to_string(r.lagged->system.last_lag) +
                     " (its autocorrelation stays above 1/e): the lagged equations see less than a "
                     "correlation time of it; give --lags a longer window (with fewer instruments "
                     "if the moments run out) or keep every n-th sample of the record");
    }
  }
  for (const std::string& s : r.estimate.warnings) {
    if (s.rfind("no optimally weighted estimate", 0) != 0) rest.push_back(s);
  }
  w.insert(w.end(), rest.begin(), rest.end());
  return w;
}

}  // namespace momentid
