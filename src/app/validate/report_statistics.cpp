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
  return "up-crossing rates";
}

std::string check_line(const StatisticCheck& c) {
  double low = c.run_distances.front(), high = low;
  for (double d : c.run_distances) {
    low = std::min(low, d);
    high = std::max(high, d);
  }
  std::string out = "  " + c.output + ": " + kind_text(c.kind) + ": distance " +
                    number(c.distance, "%.3g") + " (runs " + number(low, "%.3g") + ".." +
                    number(high, "%.3g") + ", limit " + number(c.limit, "%.3g") + "): ";
  if (c.inside()) return out + "inside\n";
  return out + "outside, " + number(c.distance / c.limit, "%.3g") + " times the limit\n";
}

std::string json_array(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t k = 0; k < values.size(); ++k) out += (k ? ", " : "") + json_number(values[k]);
  return out + "]";
}

std::string check_json(const StatisticCheck& c) {
  return "{\"output\": " + json_string(c.output) + ", \"kind\": " + json_string(c.kind) +
         ", \"distance\": " + json_number(c.distance) + ", \"limit\": " + json_number(c.limit) +
         ", \"inside\": " + (c.inside() ? "true" : "false") +
         ", \"run_distances\": " + json_array(c.run_distances) +
         ",\n       \"at\": " + json_array(c.at) +
         ",\n       \"measured\": " + json_array(c.measured) +
         ",\n       \"mean\": " + json_array(c.mean) + ",\n       \"low\": " + json_array(c.low) +
         ",\n       \"high\": " + json_array(c.high) + "}";
}

std::string sensitivity_json(const Sensitivity& s) {
  return "{\"perturbation\": " + json_number(Sensitivity::kPerturbation) +
         ", \"spread_fraction\": " + json_number(Sensitivity::kSpread) +
         ", \"run\": " + std::to_string(s.run) + ", \"separation\": " + json_number(s.separation) +
         ", \"final_separation\": " + json_number(s.final_separation) +
         ", \"time_to_spread\": " + (s.time_to_spread ? json_number(*s.time_to_spread) : "null") +
         ", \"lyapunov\": " + json_number(s.lyapunov) + "}";
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
    for (std::size_t o = 0; o < r.outputs.size(); ++o) {
      out += " " + r.outputs[o].name + " " + number(s.noise_sd[o], "%.3g");
    }
    out += "; " + number(100 * s.level, "%g") + "% bands for all " +
           std::to_string(s.checks.size()) + " together):\n";
    for (const StatisticCheck& c : s.checks) out += check_line(c);
    out += "\n";
  }
  return out + "verdict: " + r.verdict + "\n\n";
}

std::string statistics_json(const ValidateResult& r) {
  const StatisticalValidation& s = r.statistics;
  std::string out =
      ",\n  \"sensitive\": " + std::string(r.sensitivity.sensitive ? "true" : "false") +
      ",\n  \"consistent\": " + (r.consistent ? "true" : "false") +
      ",\n  \"verdict\": " + json_string(r.verdict) +
      ",\n  \"sensitivity\": " + sensitivity_json(r.sensitivity) + ",\n  \"statistics\": ";
  if (!s.compared) {
    return out + (s.not_compared.empty()
                      ? "null"
                      : "{\"not_compared\": " + json_string(s.not_compared) + "}");
  }
  out += "{\"runs\": " + std::to_string(s.runs) + ", \"segment\": " + std::to_string(s.segment) +
         ", \"window\": \"hann\", \"overlap\": 0.5, \"level\": " + json_number(s.level) +
         ", \"outside\": " + std::to_string(s.outside()) + ", \"noise_sd\": {";
  for (std::size_t o = 0; o < r.outputs.size(); ++o) {
    out += (o ? ", " : "") + json_string(r.outputs[o].name) + ": " + json_number(s.noise_sd[o]);
  }
  out += "},\n    \"checks\": [";
  for (std::size_t k = 0; k < s.checks.size(); ++k) {
    out += std::string(k ? "," : "") + "\n      " + check_json(s.checks[k]);
  }
  return out + "]}";
}

}  // namespace momentid
