// The text and JSON reports of check.

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "common/json.hpp"
#include "momentid/check.hpp"
#include "momentid/json.hpp"

namespace momentid {

std::string format_text(const CheckResult& r) {
  const DataMoments& data = r.data;
  const int width = static_cast<int>(6 * r.lags);
  std::string out;
  char line[512];
  const auto print = [&](const char* format, auto... values) {
    std::snprintf(line, sizeof line, format, values...);
    out += line;
  };
  out += "data " + r.data_name + ": ";
  print("%zu rows in %zu %s", data.rows, data.runs, data.runs == 1 ? "run" : "runs");
  if (data.time_step) print(", dt = %g", *data.time_step);
  print("\n\n%-10s %12s %12s  %-*s %s\n", "channel", "mean", "variance", width,
        "autocorrelation at lags 1, 2, ...", "corr. time");
  for (const ChannelStatistics& c : data.channels) {
    std::string lags;
    for (double rho : c.autocorrelation) {
      char text[16];
      std::snprintf(text, sizeof text, "%5.2f ", rho);
      lags += text;
    }
    const std::string time = c.correlation_time > r.lags ? "> " + std::to_string(r.lags)
                                                         : std::to_string(c.correlation_time);
    out += c.name.size() < 10 ? c.name + std::string(10 - c.name.size(), ' ') : c.name;
    print(" %12.5g %12.5g  ", c.mean, c.variance);
    out += lags.size() < static_cast<std::size_t>(width)
               ? lags + std::string(static_cast<std::size_t>(width) - lags.size(), ' ')
               : lags;
    out += " " + time + "\n";
  }
  out += "\n";
  // White sensor noise on a state, smooth apart from it: the lag-0 excess (with a model, which
  // tells the states from the inputs), when it is at least 1% of the standard deviation.
  for (const ChannelStatistics& c : data.channels) {
    if (!r.with_model || c.is_input) continue;
    // Below 1% the estimate cannot tell noise from the roughness of a state driven by a held
    // input.
    const std::optional<double> fraction = c.noise_fraction();
    if (!fraction || *fraction < 0.01) continue;
    print(
        "%s: white noise of about %.2g%% of its standard deviation (variance %.3g), if it is "
        "otherwise smooth\n",
        c.name.c_str(), 100 * *fraction, *c.noise_variance);
  }
  for (const ChannelStatistics& c : data.channels) {
    if (!c.is_input || c.autocorrelation.empty()) continue;
    if (c.autocorrelation[0] >= 0.5) {
      out += "input " + c.name + " is smooth enough for the moment method ";
      print("(lag-1 autocorrelation %.3f)\n", c.autocorrelation[0]);
    }
  }
  if (r.with_model) {
    for (const std::string& name : r.missing_states) {
      out += "state " + name +
             " is not in the file: the statistics and identities that need it are left out\n";
    }
    for (const std::string& name : r.missing_inputs) {
      out += "input " + name + " is not in the file: only the states are checked\n";
    }
    out += r.identities.empty() ? "stationarity identities: none to check\n"
                                : "stationarity identities (sample violation, z-score):\n";
    for (const IdentityCheck& c : r.identities) {
      out += "  " + c.identity + ": ";
      print("%.3g (z = %.2f)%s\n", c.violation, c.z,
            std::abs(c.z) > 4 ? "  <- violated: not stationary, or not this model" : "");
    }
  }
  for (const std::string& w : r.warnings) out += "warning: " + w + "\n";
  return out;
}

namespace {

using Json = nlohmann::ordered_json;

// An optional number: null when absent, as when it is not finite.
Json optional_json(const std::optional<double>& x) { return x ? json_value(*x) : Json(); }

Json channel_json(const ChannelStatistics& c) {
  return {{"input", c.is_input},
          {"mean", json_value(c.mean)},
          {"variance", json_value(c.variance)},
          {"autocorrelation", json_value(c.autocorrelation)},
          {"correlation_time", c.correlation_time},
          {"noise_variance", optional_json(c.noise_variance)},
          {"noise_fraction", optional_json(c.noise_fraction())}};
}

}  // namespace

nlohmann::ordered_json json_value(const CheckResult& r) {
  const DataMoments& data = r.data;
  Json out = {{"data", r.data_name}, {"rows", data.rows},
              {"runs", data.runs},   {"dt", optional_json(data.time_step)},
              {"lags", r.lags},      {"with_model", r.with_model}};
  Json& channels = out["channels"] = Json::object();
  for (const ChannelStatistics& c : data.channels) channels[c.name] = channel_json(c);
  Json& identities = out["identities"] = Json::array();
  for (const IdentityCheck& c : r.identities) {
    identities.push_back(
        {{"identity", c.identity}, {"violation", json_value(c.violation)}, {"z", json_value(c.z)}});
  }
  out["missing_inputs"] = r.missing_inputs;
  out["missing_states"] = r.missing_states;
  out["warnings"] = r.warnings;
  return out;
}

std::string format_json(const CheckResult& r) { return json_text(json_value(r)); }

}  // namespace momentid
