// The identification's report, as text and as JSON (docs/cli/identify.md, "momentid identify").

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "common/json.hpp"
#include "common/number.hpp"
#include "momentid/derive.hpp"
#include "momentid/identify.hpp"
#include "momentid/lagged.hpp"

namespace momentid {
namespace {

void table(std::ostringstream& out, const std::vector<ParameterEstimate>& parameters) {
  std::size_t width = 9;
  for (const auto& p : parameters) width = std::max(width, p.name.size());
  char line[256];
  std::snprintf(line, sizeof line, "  %-*s  %14s  %12s  %s\n", static_cast<int>(width), "parameter",
                "estimate", "std error", "95% interval");
  out << line;
  for (const auto& p : parameters) {
    const std::string interval =
        p.fixed          ? "fixed"
        : p.identifiable ? std::string("[") + number(p.ci_low) + ", " + number(p.ci_high) + "]"
                         : "not identifiable";
    std::snprintf(line, sizeof line, "  %-*s  %14s  %12s  %s\n", static_cast<int>(width),
                  p.name.c_str(), number(p.estimate).c_str(), number(p.std_error, "%.3g").c_str(),
                  interval.c_str());
    out << line;
  }
}

// "lagged moment equations at lags 3..300 samples, instruments y, y^3; not measured: v = y';
// 5-point lag stencils".
std::string method_text(const IdentifyResult& r) {
  std::string out = "lagged moment equations at lags " +
                    std::to_string(r.lagged->system->first_lag) + ".." +
                    std::to_string(r.lagged->system->last_lag) + " samples, instruments ";
  for (std::size_t i = 0; i < r.lagged->system->instruments.size(); ++i) {
    out += (i ? ", " : "") + format_monomial(*r.model, r.lagged->system->instruments[i]);
  }
  for (std::size_t i = 0; i < r.lagged->system->derivatives.size(); ++i) {
    out += (i ? ", " : "; not measured: ") + r.lagged->system->derivatives[i];
  }
  out += "; " + std::to_string(2 * r.lagged->stencil_reach + 1) + "-point lag stencils";
  return out;
}

// "noise variances, corrected for in powers of the channels: y 0.0001"; empty without noise.
std::string noise_text(const IdentifyResult& r) {
  std::string noise;
  for (std::size_t c = 0; c < r.lagged->noise.size(); ++c) {
    if (r.lagged->noise[c] == 0) continue;
    noise += (noise.empty() ? "" : ", ") + r.lagged->channels[c] + " " +
             number(r.lagged->noise[c], "%.3g");
  }
  return noise.empty() ? "" : "noise variances, corrected for in powers of the channels: " + noise;
}

// "E[y(t-3)*y^3]": a lagged moment over the named channels.
std::string lagged_moment_text(const std::vector<std::string>& channels, const Moment& m) {
  std::string out;
  for (const MomentFactor& f : m.factors()) {
    out += (out.empty() ? "" : "*") + channels[static_cast<std::size_t>(f.channel)];
    // Appended piece by piece: g++ 12 warns wrongly (-Wrestrict) about "^" + std::string.
    if (f.power > 1) out.append("^").append(std::to_string(f.power));
    if (f.lag > 0) out.append("(t-").append(std::to_string(f.lag)).append(")");
  }
  return "E[" + (out.empty() ? std::string("1") : out) + "]";
}

// The refinements of a zero-lag estimate: the sampling bias, the held-input correction and the
// record's ends.
void refinements_text(std::ostringstream& out, const IdentifyResult& r) {
  if (!r.zero_lag) return;
  if (const auto& s = r.zero_lag->sampling_bias) {
    out << "  sampling bias at dt (the estimate from every other sample, bias of order dt^"
        << IdentifyResult::ZeroLag::SamplingBias::kOrder << "):\n";
    const auto& list = r.parameters();
    for (std::size_t p = 0; p < list.size(); ++p) {
      out << "    " << list[p].name << ": " << number(s->bias[p], "%.3g") << " (every other sample "
          << number(s->coarse[p], "%g") << ", difference error "
          << number(s->difference_error[p], "%.3g") << ")\n";
    }
    out << (s->applied ? "    removed: the estimates above are extrapolated to dt = 0\n"
                       : "    within the errors: not removed\n");
  }
  if (const auto& h = r.zero_lag->held_input) {
    if (h->unavailable.empty()) {
      out << "  held input: moments corrected by -dt^2/12 E[g''] for the kinks it puts at the "
             "samples, which moved the estimates by";
      const auto& list = r.parameters();
      for (std::size_t p = 0; p < list.size(); ++p) {
        out << (p ? ", " : " ") << list[p].name << " " << number(h->shift[p], "%+.3g");
      }
      out << "\n";
    } else {
      out << "  held input: moments not corrected for the kinks it puts at the samples: "
          << h->unavailable << "\n";
    }
  }
  if (const auto& v = r.zero_lag->end_values) {
    out << (v->unavailable.empty()
                ? "  record ends: the errors they leave come from the variances of the states "
                  "there, the batches give the rest\n"
                : "  record ends: the errors they leave come from the batches: " + v->unavailable +
                      "\n");
  }
}

// The model's constants and the fixed parameters, with their values: the intervals are
// conditional on them (docs/model-language.md, "Constants are assumptions").
std::vector<std::pair<std::string, double>> assumed(const IdentifyResult& r) {
  std::vector<std::pair<std::string, double>> out;
  for (const Declaration& c : r.model->constants()) out.emplace_back(c.name, c.value->to_double());
  for (const ParameterEstimate& p : r.parameters()) {
    if (p.fixed) out.emplace_back(p.name, p.estimate);
  }
  return out;
}

// The status, the warnings, the system's and the errors' figures, the J test, the refinements and
// the stationarity identities.
void diagnostics_text(std::ostringstream& out, const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  out << "\ndiagnostics\n";
  out << "  status: " << to_string(status(r)) << "\n";
  const std::vector<std::string> all = warnings(r);
  if (all.empty()) out << "  warnings: none\n";
  for (const std::string& w : all) out << "  warning: " << w << "\n";
  out << "  equations: " << e.rows << ", rank " << e.rank << " of "
      << e.least_squares.parameters.size() << ", condition number " << number(e.condition, "%.3g")
      << "\n";
  out << "  batches: " << e.batches;
  if (e.least_squares.dof > 0) {
    const bool ends =
        r.zero_lag && r.zero_lag->end_values && r.zero_lag->end_values->unavailable.empty();
    out << "; standard errors from their long-run covariance"
        << (ends ? " and the record's ends" : "") << " on " << number(e.least_squares.dof, "%.0f")
        << " degrees of freedom";
    if (e.optimal) {
      out << " (optimally weighted: " << number(e.optimal->dof, "%.0f") << ")";
    }
  }
  out << "\n";
  if (const auto values = assumed(r); !values.empty()) {
    out << "  taken as exact:";
    for (std::size_t i = 0; i < values.size(); ++i) {
      out << (i ? ", " : " ") << values[i].first << " = " << number(values[i].second);
    }
    out << " (the intervals hold only if these values do)\n";
  }
  if (e.j_statistic) {
    out << "  J test: J = " << number(*e.j_statistic, "%.4g") << " on " << e.j_dof
        << " degrees of freedom, p = " << number(*e.j_pvalue, "%.3g")
        << (*e.j_pvalue < 0.01 ? " (the model does not fit the data)" : "") << "\n";
  }
  refinements_text(out, r);
  if (!e.identities.empty()) {
    out << "  stationarity identities (sample violation, z-score):\n";
    for (const IdentityCheck& c : e.identities) {
      out << "    " << c.identity << ": " << number(c.violation, "%.3g")
          << " (z = " << number(c.z, "%.2f") << ")\n";
    }
  }
}

void refinements_json(std::ostringstream& out, const IdentifyResult& r) {
  if (!r.zero_lag) return;
  if (const auto& s = r.zero_lag->sampling_bias) {
    out << ",\n    \"sampling_bias\": {\"order\": " << IdentifyResult::ZeroLag::SamplingBias::kOrder
        << ", \"applied\": " << (s->applied ? "true" : "false") << ", \"parameters\": {";
    const auto& list = r.parameters();
    for (std::size_t p = 0; p < list.size(); ++p) {
      out << (p ? ", " : "") << json_string(list[p].name)
          << ": {\"coarse\": " << json_number(s->coarse[p])
          << ", \"bias\": " << json_number(s->bias[p])
          << ", \"difference_error\": " << json_number(s->difference_error[p]) << "}";
    }
    out << "}}";
  }
  if (const auto& h = r.zero_lag->held_input) {
    out << ",\n    \"held_input_correction\": {\"applied\": "
        << (h->unavailable.empty() ? "true" : "false");
    if (h->unavailable.empty()) {
      out << ", \"shift\": {";
      const auto& list = r.parameters();
      for (std::size_t p = 0; p < list.size(); ++p) {
        out << (p ? ", " : "") << json_string(list[p].name) << ": " << json_number(h->shift[p]);
      }
      out << "}";
    } else {
      out << ", \"reason\": " << json_string(h->unavailable);
    }
    out << "}";
  }
  if (const auto& v = r.zero_lag->end_values) {
    out << ",\n    \"end_values\": {\"applied\": " << (v->unavailable.empty() ? "true" : "false");
    if (!v->unavailable.empty()) out << ", \"reason\": " << json_string(v->unavailable);
    out << "}";
  }
}

void diagnostics_json(std::ostringstream& out, const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  const DataMoments& d = r.data;
  out << ",\n  \"diagnostics\": {\n    \"status\": " << json_string(to_string(status(r)))
      << ",\n    \"rows\": " << e.rows << ",\n    \"rank\": " << e.rank
      << ",\n    \"condition\": " << json_number(e.condition) << ",\n    \"batches\": " << e.batches
      << ",\n    \"error_dof\": " << json_number(e.main().dof) << ",\n    \"samples\": " << d.rows
      << ",\n    \"runs\": " << d.runs
      << ",\n    \"input_hold\": " << json_string(to_string(d.hold))
      << ",\n    \"j_statistic\": " << (e.j_statistic ? json_number(*e.j_statistic) : "null")
      << ",\n    \"j_dof\": " << e.j_dof
      << ",\n    \"j_pvalue\": " << (e.j_pvalue ? json_number(*e.j_pvalue) : "null");
  refinements_json(out, r);
  out << ",\n    \"taken_as_exact\": {";
  const auto values = assumed(r);
  for (std::size_t i = 0; i < values.size(); ++i) {
    out << (i ? ", " : "") << json_string(values[i].first) << ": " << json_number(values[i].second);
  }
  out << "}";
  out << ",\n    \"identities\": [";
  for (std::size_t i = 0; i < e.identities.size(); ++i) {
    const IdentityCheck& c = e.identities[i];
    out << (i ? ", " : "") << "{\"identity\": " << json_string(c.identity)
        << ", \"violation\": " << json_number(c.violation) << ", \"z\": " << json_number(c.z)
        << "}";
  }
  out << "],\n    \"correlation\": [";
  const auto& correlation = e.main().correlation;
  for (std::size_t i = 0; i < correlation.size(); ++i) {
    out << (i ? ", " : "") << "[";
    for (std::size_t j = 0; j < correlation[i].size(); ++j) {
      out << (j ? ", " : "") << json_number(correlation[i][j]);
    }
    out << "]";
  }
  out << "],\n    \"warnings\": " << json_strings(warnings(r)) << "\n  }\n}\n";
}

// The backbone's ends: the frequency at the smallest and at the largest amplitude.
void backbone_text(std::ostringstream& out, const IdentifyResult& r) {
  const NonlinearCurves curves = nonlinear_curves(r);
  if (curves.amplitude.empty()) return;
  out << "  backbone (harmonic balance): " << number(curves.frequency_hz.front(), "%.6g") << " +- "
      << number(curves.frequency_se.front(), "%.3g") << " Hz at amplitude "
      << number(curves.amplitude.front(), "%.4g") << ", "
      << number(curves.frequency_hz.back(), "%.6g") << " +- "
      << number(curves.frequency_se.back(), "%.3g") << " Hz at "
      << number(curves.amplitude.back(), "%.4g") << " (3 standard deviations of " << curves.state
      << ")\n";
}

// The linearised modes (linearised_modes) under the identified model, when there are any.
void modes_text(std::ostringstream& out, const IdentifyResult& r) {
  const LinearisedModes linear = linearised_modes(r);
  if (linear.modes.empty()) return;
  out << "\nlinearised at the equilibrium (";
  for (std::size_t j = 0; j < linear.equilibrium.size(); ++j) {
    out << (j ? ", " : "") << r.model->states()[j].name << " = "
        << number(linear.equilibrium[j], "%.4g");
  }
  out << ")\n";
  for (std::size_t k = 0; k < linear.modes.size(); ++k) {
    const LinearisedModes::Mode& m = linear.modes[k];
    out << "  mode " << k + 1 << ": " << number(m.frequency_hz, "%.6g") << " +- "
        << number(m.frequency_se, "%.3g") << " Hz, damping ratio "
        << number(m.damping_ratio, "%.6g") << " +- " << number(m.damping_se, "%.3g") << "\n";
  }
  backbone_text(out, r);
}

std::string json_numbers(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + json_number(values[i]);
  return out + "]";
}

// The "engineering" value of the JSON layout: the linearised modes, or why there are none.
std::string modes_json(const IdentifyResult& r) {
  const LinearisedModes linear = linearised_modes(r);
  std::string out = "{\"equilibrium\": {";
  for (std::size_t j = 0; j < linear.equilibrium.size(); ++j) {
    out += (j ? ", " : "") + json_string(r.model->states()[j].name) + ": " +
           json_number(linear.equilibrium[j]);
  }
  std::string frequencies, damping;
  for (std::size_t k = 0; k < linear.modes.size(); ++k) {
    const LinearisedModes::Mode& m = linear.modes[k];
    frequencies += (k ? ", " : "") + std::string("{\"estimate\": ") + json_number(m.frequency_hz) +
                   ", \"std_error\": " + json_number(m.frequency_se) + "}";
    damping += (k ? ", " : "") + std::string("{\"estimate\": ") + json_number(m.damping_ratio) +
               ", \"std_error\": " + json_number(m.damping_se) + "}";
  }
  out += "}, \"natural_frequencies_hz\": [" + frequencies + "], \"damping_ratios\": [" + damping +
         "], \"unavailable\": " + json_string(linear.unavailable);
  const NonlinearCurves curves = nonlinear_curves(r);
  if (curves.amplitude.empty()) return out + "}";
  return out + ",\n    \"restoring_force\": {\"state\": " + json_string(curves.state) +
         ", \"displacement\": " + json_numbers(curves.displacement) +
         ", \"force\": " + json_numbers(curves.force) +
         ", \"std_error\": " + json_numbers(curves.force_se) +
         "},\n    \"backbone\": {\"amplitude\": " + json_numbers(curves.amplitude) +
         ", \"frequency_hz\": " + json_numbers(curves.frequency_hz) +
         ", \"std_error\": " + json_numbers(curves.frequency_se) + "}}";
}

}  // namespace

std::string format_text(const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  const DataMoments& d = r.data;
  std::ostringstream out;
  out << "model " << r.model->name() << ", data " << r.data_name << ": " << d.rows << " rows in "
      << d.runs << (d.runs == 1 ? " run" : " runs");
  if (d.time_step) out << ", dt = " << number(*d.time_step);
  out << ", input hold " << to_string(d.hold) << "\n";
  out << (r.lagged ? method_text(r) : "zero-lag moment equations") << "\n";
  out << "  chosen: " << r.why << "\n";
  if (r.lagged && !r.lagged->cut.empty()) out << "  " << r.lagged->cut << "\n";
  if (r.lagged && !noise_text(r).empty()) out << noise_text(r) << "\n";
  if (!r.centered.empty()) {
    out << "means removed (--center):";
    for (const auto& [name, mean] : r.centered) out << " " << name << " " << number(mean, "%.4g");
    out << "\n";
  }
  out << "\n";
  if (e.optimal) {
    out << "optimally weighted estimate (two-step GMM)\n";
    table(out, e.optimal->parameters);
    out << "\nleast-squares estimate (first step)\n";
  } else {
    out << "least-squares estimate\n";
  }
  table(out, e.least_squares.parameters);
  const std::vector<std::string> equations = identified_equations(r);
  if (!equations.empty()) {
    out << "\nidentified model\n";
    for (const std::string& line : equations) out << "  " << line << "\n";
  }
  modes_text(out, r);
  diagnostics_text(out, r);
  return out.str();
}

std::string format_json(const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  const DataMoments& d = r.data;
  auto parameters = [](const std::vector<ParameterEstimate>& list) {
    std::string out = "{";
    for (std::size_t i = 0; i < list.size(); ++i) {
      const ParameterEstimate& p = list[i];
      out += (i ? ",\n    " : "\n    ") + json_string(p.name) +
             ": {\"estimate\": " + json_number(p.estimate) +
             ", \"std_error\": " + json_number(p.std_error) + ", \"ci95\": [" +
             json_number(p.ci_low) + ", " + json_number(p.ci_high) +
             "], \"identifiable\": " + (p.identifiable ? "true" : "false") +
             ", \"fixed\": " + (p.fixed ? "true" : "false") + "}";
    }
    return out + "\n  }";
  };
  std::ostringstream out;
  out << "{\n  \"model\": " << json_string(r.model->name())
      << ",\n  \"data\": " << json_string(r.data_name)
      << ",\n  \"parameters\": " << parameters(e.main().parameters);
  if (e.optimal) out << ",\n  \"least_squares\": " << parameters(e.least_squares.parameters);
  out << ",\n  \"method\": {\"name\": \"" << (r.lagged ? "lagged" : "zero-lag")
      << "\", \"why\": " << json_string(r.why);
  if (r.lagged) {
    out << ", \"lags\": [" << r.lagged->system->first_lag << ", " << r.lagged->system->last_lag
        << "], \"stencil_points\": " << 2 * r.lagged->stencil_reach + 1 << ", \"instruments\": [";
    for (std::size_t i = 0; i < r.lagged->system->instruments.size(); ++i) {
      out << (i ? ", " : "")
          << json_string(format_monomial(*r.model, r.lagged->system->instruments[i]));
    }
    out << "], \"cut\": " << json_string(r.lagged->cut)
        << ", \"not_measured\": " << json_strings(r.lagged->system->derivatives)
        << ", \"noise_variance\": {";
    for (std::size_t c = 0; c < r.lagged->noise.size(); ++c) {
      out << (c ? ", " : "") << json_string(r.lagged->channels[c]) << ": "
          << json_number(r.lagged->noise[c]);
    }
    out << "}";
  }
  out << "}";
  if (!r.centered.empty()) {
    out << ",\n  \"centered\": {";
    std::size_t k = 0;
    for (const auto& [name, mean] : r.centered) {
      out << (k++ ? ", " : "") << json_string(name) << ": " << json_number(mean);
    }
    out << "}";
  }
  out << ",\n  \"equations\": " << json_strings(identified_equations(r));
  out << ",\n  \"engineering\": " << modes_json(r);
  out << ",\n  \"moments\": {";
  for (std::size_t k = 0; k < d.estimates.mean.size(); ++k) {
    const std::string name = r.lagged ? lagged_moment_text(r.lagged->channels, r.lagged->moments[k])
                                      : format_moment(*r.model, r.zero_lag->moments[k]);
    out << (k ? ", " : "") << json_string(name) << ": " << json_number(d.estimates.mean[k]);
  }
  out << "}";
  diagnostics_json(out, r);
  return out.str();
}

}  // namespace momentid
