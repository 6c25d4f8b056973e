#include "app/validate/report_statistics.hpp"

#include <cstdio>

#include "common/json.hpp"
#include "common/number.hpp"

namespace momentid {
namespace {

std::string kind_text(const std::string& kind) {
  if (kind == "psd") return "power spectral density";
  if (kind == "distribution") return "amplitude quantiles";
  if (kind == "prediction") return "prediction error";
  if (kind == "bias") return "prediction bias (the error's slopes on the states)";
  return "up-crossing rates";
}

std::string check_line(const StatisticCheck& c) {
  double low = c.run_distances.front(), high = low;
  for (double d : c.run_distances) {
    low = std::min(low, d);
    high = std::max(high, d);
  }
  std::string out = "  " + c.output + ": " + kind_text(c.kind) +
                    (c.kind == "prediction" ? " (offset " + number(c.offset, "%.3g") + " fitted)"
                                            : std::string()) +
                    ": distance " + number(c.distance, "%.3g") + " (runs " + number(low, "%.3g") +
                    ".." + number(high, "%.3g") + ", limit " + number(c.limit, "%.3g") + "): ";
  if (c.inside()) return out + "inside\n";
  return out + "outside, " + number(c.distance / c.limit, "%.3g") + " times the limit\n";
}

using Json = nlohmann::ordered_json;

Json check_json(const StatisticCheck& c) {
  Json out = {{"output", c.output},
              {"kind", c.kind},
              {"distance", json_value(c.distance)},
              {"limit", json_value(c.limit)},
              {"inside", c.inside()},
              {"run_distances", json_value(c.run_distances)},
              {"at", json_value(c.at)},
              {"measured", json_value(c.measured)},
              {"mean", json_value(c.mean)},
              {"low", json_value(c.low)},
              {"high", json_value(c.high)}};
  if (c.kind == "prediction") out["offset"] = json_value(c.offset);
  return out;
}

Json sensitivity_json(const Sensitivity& s) {
  return {{"perturbation", json_value(Sensitivity::kPerturbation)},
          {"spread_fraction", json_value(Sensitivity::kSpread)},
          {"run", s.run},
          {"separation", json_value(s.separation)},
          {"final_separation", json_value(s.final_separation)},
          {"time_to_spread", s.time_to_spread ? json_value(*s.time_to_spread) : Json()},
          {"lyapunov", json_value(s.lyapunov)}};
}

// The statistics compared: null when they were not, or why not.
Json compared_json(const ValidateResult& r) {
  const StatisticalValidation& s = r.statistics;
  if (!s.compared) return s.not_compared.empty() ? Json() : Json{{"not_compared", s.not_compared}};
  Json out = {{"runs", s.runs},
              {"segment", s.segment},
              {"window", "hann"},
              {"overlap", 0.5},
              {"level", json_value(s.level)},
              {"outside", s.outside()},
              {"noise_sd", Json::object()}};
  // The statistics compare the states, which come first among the outputs.
  for (std::size_t o = 0; o < s.noise_sd.size(); ++o) {
    out["noise_sd"][r.outputs[o].name] = json_value(s.noise_sd[o]);
  }
  Json& checks = out["checks"] = Json::array();
  for (const StatisticCheck& c : s.checks) checks.push_back(check_json(c));
  return out;
}

}  // namespace

std::string sensitivity_text(const ValidateResult& r) {
  const Sensitivity& s = r.sensitivity;
  std::string out = "sensitivity: a perturbation of " + number(Sensitivity::kPerturbation, "%g") +
                    " of each state's spread ";
  if (s.time_to_spread) {
    out += "grows to " + number(100 * Sensitivity::kSpread, "%g") + "% of it in " +
           number(*s.time_to_spread, "%.4g") + " s";
  } else {
    out += (s.final_separation < Sensitivity::kPerturbation ? "shrinks to " : "is at ") +
           number(s.final_separation, "%.3g") + " of it at the end";
  }
  if (r.replay.record.runs.size() > 1) out += " of run " + std::to_string(s.run);
  out +=
      " (finite-time Lyapunov exponent " + number(s.lyapunov, "%.3g") + "/s): the trajectory " +
      (s.sensitive ? "cannot be reproduced, the statistics judge the model" : "can be reproduced");
  return out + "\n";
}

std::string statistics_text(const ValidateResult& r) {
  const StatisticalValidation& s = r.statistics;
  std::string out;
  if (s.compared) {
    if (!r.sensitivity.sensitive) {
      out += "(the trajectory fit judges this model; the statistics show where it differs)\n";
    }
    out += "statistics against " + std::to_string(s.runs) +
           " simulations from other initial states (Welch spectra of " + std::to_string(s.segment) +
           "-sample Hann segments, half overlapping; noise added:";
    for (std::size_t o = 0; o < s.noise_sd.size(); ++o) {
      out += " " + r.outputs[o].name + " " + number(s.noise_sd[o], "%.3g");
    }
    out += "; " + number(100 * s.level, "%g") + "% bands for all " +
           std::to_string(s.checks.size()) + " together):\n";
    for (const StatisticCheck& c : s.checks) out += check_line(c);
    out += "\n";
  }
  return out + "verdict: " + r.verdict + "\n\n";
}

void statistics_json(nlohmann::ordered_json& out, const ValidateResult& r) {
  out["sensitive"] = r.sensitivity.sensitive;
  out["consistent"] = r.consistent;
  out["verdict"] = r.verdict;
  out["sensitivity"] = sensitivity_json(r.sensitivity);
  out["statistics"] = compared_json(r);
}

}  // namespace momentid
