// The identification's report, as text and as JSON (docs/cli/identify.md, "momentid identify").

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "common/json.hpp"
#include "common/number.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/derive.hpp"
#include "momentid/identify.hpp"
#include "momentid/json.hpp"
#include "momentid/lagged.hpp"
#include "momentid/refine.hpp"

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

// The errors' degrees of freedom as a reader uses them: above 10^5 their t quantiles are the
// normal ones to four digits, and a noise-free record gives billions.
std::string dof_text(double dof) { return dof > 1e5 ? "more than 10^5" : number(dof, "%.0f"); }

// The status, the warnings, the system's and the errors' figures, the J test, the refinements and
// the stationarity identities.
void diagnostics_text(std::ostringstream& out, const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  out << "\ndiagnostics\n";
  out << "  status: " << to_string(status(r)) << "\n";
  const std::vector<std::string> all = warnings(r);
  if (all.empty()) out << "  warnings: none\n";
  for (const std::string& w : all) out << "  warning: " << w << "\n";
  // With latent states, the equations are in the coefficients of the equations without them.
  out << "  equations: " << e.rows << ", rank " << e.rank << " of "
      << (r.latent ? std::to_string(r.latent->coefficients.size()) + " coefficients"
                   : std::to_string(e.least_squares.parameters.size()))
      << ", condition number " << number(e.condition, "%.3g") << "\n";
  out << "  batches: " << e.batches;
  if (e.least_squares.dof > 0) {
    const bool ends =
        r.zero_lag && r.zero_lag->end_values && r.zero_lag->end_values->unavailable.empty();
    out << "; standard errors from their long-run covariance"
        << (ends ? " and the record's ends" : "") << " on " << dof_text(e.least_squares.dof)
        << " degrees of freedom";
    if (e.optimal) {
      out << " (optimally weighted: " << dof_text(e.optimal->dof) << ")";
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
    out << "    its law: J/" << e.j_dof << " x " << number(e.j_law.scale, "%.3g") << " ~ F("
        << number(e.j_law.dof, "%.3g") << ", " << number(e.j_law.denominator_dof, "%.3g")
        << "), the residual's variance on " << number(e.j_law.dof, "%.3g")
        << " effective directions (docs/uncertainty.md)\n";
  }
  if (const auto* check = r.zero_lag_check()) {
    out << "  zero-lag check: ";
    if (check->pvalue) {
      out << "T^2 = " << number(*check->statistic, "%.4g") << " on "
          << number(check->dof.first, "%.0f") << " and " << number(check->dof.second, "%.0f")
          << " degrees of freedom, p = " << number(*check->pvalue, "%.3g")
          << (check->rejects() ? " (the model does not fit the data)" : "") << "; the "
          << check->equations << " zero-lag equations up to degree " << check->degree;
      out << " give";
      const auto& list = r.parameters();
      for (std::size_t p = 0; p < list.size(); ++p) {
        out << (p ? ", " : " ") << list[p].name << " " << number(check->estimates[p], "%.6g");
      }
    } else {
      out << "none: " << check->unavailable;
    }
    out << "\n";
  }
  for (const IdentifyResult::LawCheck& c : r.law_checks) {
    out << "  law check: " << c.term << " added to the equation of " << c.equation
        << ": z = " << number(c.z, "%.3g")
        << (std::abs(c.z) > IdentifyResult::kLawZ ? " (the data call for it)" : "") << "\n";
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

using Json = nlohmann::ordered_json;

// {name: {"estimate", "std_error", "ci95", "identifiable", "fixed"}} in the model's order.
Json parameters_json(const std::vector<ParameterEstimate>& list) {
  Json out = Json::object();
  for (const ParameterEstimate& p : list) {
    out[p.name] = {{"estimate", json_value(p.estimate)},
                   {"std_error", json_value(p.std_error)},
                   {"ci95", {json_value(p.ci_low), json_value(p.ci_high)}},
                   {"identifiable", p.identifiable},
                   {"fixed", p.fixed}};
  }
  return out;
}

// What the parameters' table leaves out of a fit: its errors' degrees of freedom, its objective,
// its correlation and covariance matrices.
Json fit_json(const Fit& fit) {
  return {{"error_dof", json_value(fit.dof)},
          {"objective", json_value(fit.objective)},
          {"correlation", json_value(fit.correlation)},
          {"covariance", json_value(fit.covariance())}};
}

// {name: value} over the parameters of the main result.
Json by_parameter(const IdentifyResult& r, const std::vector<double>& values) {
  Json out = Json::object();
  const auto& list = r.parameters();
  for (std::size_t p = 0; p < list.size(); ++p) out[list[p].name] = json_value(values[p]);
  return out;
}

Json method_json(const IdentifyResult& r) {
  Json out = {{"name", r.lagged ? "lagged" : "zero-lag"}, {"why", r.why}};
  if (!r.lagged) return out;
  const LaggedSystem& system = *r.lagged->system;
  out["lags"] = {system.first_lag, system.last_lag};
  out["stencil_points"] = 2 * r.lagged->stencil_reach + 1;
  Json& instruments = out["instruments"] = Json::array();
  for (const Monomial& m : system.instruments) instruments.push_back(format_monomial(*r.model, m));
  out["cut"] = r.lagged->cut;
  out["not_measured"] = system.derivatives;
  Json& noise = out["noise_variance"] = Json::object();
  for (std::size_t c = 0; c < r.lagged->noise.size(); ++c) {
    noise[r.lagged->channels[c]] = json_value(r.lagged->noise[c]);
  }
  out["rough_noise"] = nullptr;
  if (const auto& rough = r.lagged->rough_noise) {
    out["rough_noise"] = {{"channel", rough->channel},
                          {"sixth_difference", json_value(rough->sixth)},
                          {"fourth_difference", json_value(rough->fourth)},
                          {"share", json_value(rough->share)},
                          {"parameter", rough->parameter},
                          {"shift", json_value(rough->shift)}};
  }
  return out;
}

// The "engineering" value: the linearised modes, or why there are none, and for an oscillator
// the restoring force and the backbone.
Json engineering_json(const IdentifyResult& r) {
  const LinearisedModes linear = linearised_modes(r);
  Json out = {{"equilibrium", Json::object()},
              {"natural_frequencies_hz", Json::array()},
              {"damping_ratios", Json::array()},
              {"unavailable", linear.unavailable}};
  for (std::size_t j = 0; j < linear.equilibrium.size(); ++j) {
    out["equilibrium"][r.model->states()[j].name] = json_value(linear.equilibrium[j]);
  }
  for (const LinearisedModes::Mode& m : linear.modes) {
    out["natural_frequencies_hz"].push_back(
        {{"estimate", json_value(m.frequency_hz)}, {"std_error", json_value(m.frequency_se)}});
    out["damping_ratios"].push_back(
        {{"estimate", json_value(m.damping_ratio)}, {"std_error", json_value(m.damping_se)}});
  }
  const NonlinearCurves curves = nonlinear_curves(r);
  if (curves.amplitude.empty()) return out;
  out["restoring_force"] = {{"state", curves.state},
                            {"displacement", json_value(curves.displacement)},
                            {"force", json_value(curves.force)},
                            {"std_error", json_value(curves.force_se)}};
  out["backbone"] = {{"amplitude", json_value(curves.amplitude)},
                     {"frequency_hz", json_value(curves.frequency_hz)},
                     {"std_error", json_value(curves.frequency_se)}};
  return out;
}

// The estimated moments by name, in the order of data.estimates.
Json moments_json(const IdentifyResult& r) {
  Json out = Json::object();
  const std::vector<double>& mean = r.data.estimates.mean;
  for (std::size_t k = 0; k < mean.size(); ++k) {
    out[r.lagged ? lagged_moment_text(r.lagged->channels, r.lagged->moments[k])
                 : format_moment(*r.model, r.zero_lag->moments[k])] = json_value(mean[k]);
  }
  return out;
}

// The refinements of a zero-lag estimate, into the diagnostics `out`.
void refinements_json(Json& out, const IdentifyResult& r) {
  if (!r.zero_lag) return;
  if (const auto& s = r.zero_lag->sampling_bias) {
    Json parameters = Json::object();
    const auto& list = r.parameters();
    for (std::size_t p = 0; p < list.size(); ++p) {
      parameters[list[p].name] = {{"coarse", json_value(s->coarse[p])},
                                  {"bias", json_value(s->bias[p])},
                                  {"difference_error", json_value(s->difference_error[p])}};
    }
    out["sampling_bias"] = {{"order", IdentifyResult::ZeroLag::SamplingBias::kOrder},
                            {"applied", s->applied},
                            {"parameters", std::move(parameters)}};
  }
  if (const auto& h = r.zero_lag->held_input) {
    Json& held = out["held_input_correction"] = {{"applied", h->unavailable.empty()}};
    if (h->unavailable.empty()) {
      held["shift"] = by_parameter(r, h->shift);
    } else {
      held["reason"] = h->unavailable;
    }
  }
  if (const auto& v = r.zero_lag->end_values) {
    Json& ends = out["end_values"] = {{"applied", v->unavailable.empty()}};
    if (!v->unavailable.empty()) ends["reason"] = v->unavailable;
  }
}

Json diagnostics_json(const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  Json out = {{"status", to_string(status(r))},
              {"rows", e.rows},
              {"rank", e.rank},
              {"condition", json_value(e.condition)},
              {"batches", e.batches},
              {"error_dof", json_value(e.main().dof)},
              {"objective", json_value(e.main().objective)},
              {"samples", r.data.rows},
              {"runs", r.data.runs},
              {"input_hold", to_string(r.data.hold)},
              {"j_statistic", e.j_statistic ? json_value(*e.j_statistic) : Json()},
              {"j_dof", e.j_dof},
              {"j_pvalue", e.j_pvalue ? json_value(*e.j_pvalue) : Json()},
              {"j_law", e.j_pvalue ? Json{{"dof", json_value(e.j_law.dof)},
                                          {"denominator_dof", json_value(e.j_law.denominator_dof)},
                                          {"scale", json_value(e.j_law.scale)}}
                                   : Json()}};
  if (const auto* check = r.zero_lag_check()) {
    Json estimates = Json::object();
    if (!check->estimates.empty()) estimates = by_parameter(r, check->estimates);
    out["zero_lag_check"] = {
        {"degree", check->degree},
        {"equations", check->equations},
        {"estimates", estimates},
        {"statistic", check->statistic ? json_value(*check->statistic) : Json()},
        {"dof", check->pvalue ? Json{json_value(check->dof.first), json_value(check->dof.second)}
                              : Json()},
        {"p_value", check->pvalue ? json_value(*check->pvalue) : Json()},
        {"unavailable", check->unavailable}};
  }
  if (!r.law_checks.empty()) {
    Json& checks = out["law_check"] = Json::array();
    for (const IdentifyResult::LawCheck& c : r.law_checks) {
      checks.push_back({{"equation", c.equation}, {"term", c.term}, {"z", json_value(c.z)}});
    }
  }
  if (!r.response_means.empty() || !r.response_failure.empty()) {
    Json means = Json::array();
    for (const IdentifyResult::ResponseMean& m : r.response_means) {
      means.push_back({{"state", m.name},
                       {"recorded", json_value(m.recorded)},
                       {"simulated", json_value(m.simulated)},
                       {"std_error", json_value(m.std_error)}});
    }
    out["response_means"] = {
        {"states", means},
        {"failure", r.response_failure.empty() ? Json() : Json(r.response_failure)}};
  }
  refinements_json(out, r);
  Json& exact = out["taken_as_exact"] = Json::object();
  for (const auto& [name, value] : assumed(r)) exact[name] = json_value(value);
  Json& identities = out["identities"] = Json::array();
  for (const IdentityCheck& c : e.identities) {
    identities.push_back(
        {{"identity", c.identity}, {"violation", json_value(c.violation)}, {"z", json_value(c.z)}});
  }
  out["correlation"] = json_value(e.main().correlation);
  out["covariance"] = json_value(e.main().covariance());
  if (e.optimal) out["least_squares"] = fit_json(e.least_squares);
  out["warnings"] = warnings(r);
  return out;
}

// "formed (--integrate): y from 'a' (integrated twice); every channel high-passed at ...", or
// "formed by default (as --integrate y forms them): ..."
std::string integration_text(const IdentifyResult::Integration& f) {
  std::string out = "formed (--integrate):";
  if (f.by_default) {
    out = "formed by default (as --integrate ";
    for (std::size_t i = 0; i < f.formed.size(); ++i) out += (i ? "," : "") + f.formed[i].state;
    out += " forms them):";
  }
  for (std::size_t i = 0; i < f.formed.size(); ++i) {
    const auto& s = f.formed[i];
    out += std::string(i ? ", " : " ") + s.state + " from '" + s.column + "' (integrated " +
           (s.integrals == 2 ? "twice" : "once") + ")";
  }
  out += "; every channel high-passed at " + number(f.corner, "%.3g") +
         " Hz (linear phase, a fourth-order Butterworth filter's magnitude" +
         (f.corner_chosen ? ", " + f.band : std::string()) + "), the first " +
         std::to_string(f.settle) + " rows of each run filling it";
  if (f.misfit && f.misfit->failure.empty()) {
    out +=
        "\n  the misfit the filter leaves in the nonlinear terms taken out: read off the same "
        "equations on the identified model's response to the recorded inputs (" +
        std::to_string(f.misfit->rows) +
        " rows, without sensor noise); the estimates moved by up to " +
        number(f.misfit->shift, "%.2g") + " standard errors" +
        (f.misfit->parameter.empty() ? std::string() : " (" + f.misfit->parameter + ")");
  }
  return out;
}

// The latent states' section: the equations without them, their coefficients' estimates and
// the minimum distance that gave the parameters.
std::string latent_text(const IdentifyResult::Latent& l) {
  std::string out = l.equations;
  out += "coefficients estimated (lagged equations of the equations without them)\n";
  for (const ParameterEstimate& c : l.coefficients) {
    out += "  " + c.name + " = " + number(c.estimate, "%.6g") + " +- " +
           number(c.std_error, "%.3g") + "\n";
  }
  out += "parameters from the coefficients by minimum distance";
  if (l.distance && l.pvalue) {
    out += ": Q = " + number(*l.distance, "%.4g") + " on " + std::to_string(l.dof) +
           (l.dof == 1 ? " degree" : " degrees") + " of freedom, p = " + number(*l.pvalue, "%.3g");
  } else if (l.dof == 0) {
    out += " (as many coefficients as parameters: no test)";
  }
  if (l.starts > 0) {
    out += "; searched from " + std::to_string(l.starts) +
           " values around the model's nominal ones too, from which it stopped" +
           (l.nominal_distance && std::isfinite(*l.nominal_distance)
                ? " at Q = " + number(*l.nominal_distance, "%.4g")
                : " without converging");
  }
  return out + "\n";
}

}  // namespace

std::string format_text(const IdentifyResult& r) {
  const AlgebraLock lock;
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
  if (r.integration) out << integration_text(*r.integration) << "\n";
  if (r.latent) out << latent_text(*r.latent);
  // The derivative columns' means apart: they are removed whether or not --center names them.
  std::string asked, offsets;
  for (const auto& [name, mean] : r.centered) {
    const int v = r.model->variable_index(name);
    const bool derivative =
        r.model->variables()[static_cast<std::size_t>(v)].kind == VariableKind::kDerivative;
    (derivative ? offsets : asked) += " " + name + " " + number(mean, "%.4g");
  }
  if (!asked.empty()) out << "means removed (--center):" << asked << "\n";
  if (!offsets.empty()) {
    out << "offsets removed from the derivative columns (a state's derivative has mean 0):"
        << offsets << "\n";
  }
  out << "\n";
  if (e.optimal) {
    out << "optimally weighted estimate (GMM)\n";
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
  if (r.refinement) out << "\n" << refinement_text(*r.refinement);
  diagnostics_text(out, r);
  return out.str();
}

nlohmann::ordered_json json_value(const IdentifyResult& r) {
  const AlgebraLock lock;
  Json out = {{"model", r.model->name()},
              {"data", r.data_name},
              {"parameters", parameters_json(r.estimate.main().parameters)}};
  if (r.estimate.optimal)
    out["least_squares"] = parameters_json(r.estimate.least_squares.parameters);
  out["method"] = method_json(r);
  if (const auto& f = r.integration) {
    Json formed = Json::array();
    for (const auto& s : f->formed) {
      formed.push_back({{"state", s.state}, {"column", s.column}, {"integrals", s.integrals}});
    }
    out["integration"] = {{"formed", formed},
                          {"corner_hz", json_value(f->corner)},
                          {"corner_chosen", f->corner_chosen},
                          {"band", f->band},
                          {"settle_rows", f->settle},
                          {"by_default", f->by_default}};
    if (const auto& m = f->misfit) {
      out["integration"]["misfit"] = {
          {"rows", m->rows},       {"parameter", m->parameter}, {"shift", json_value(m->shift)},
          {"failure", m->failure}, {"channel", m->channel},     {"spread", json_value(m->spread)}};
    }
  }
  if (const auto& l = r.latent) {
    out["latent"] = {
        {"states", l->states},
        {"equations", l->equations},
        {"coefficients", parameters_json(l->coefficients)},
        {"distance", l->distance ? json_value(*l->distance) : Json()},
        {"dof", l->dof},
        {"pvalue", l->pvalue ? json_value(*l->pvalue) : Json()},
        {"converged", l->converged},
        {"starts", l->starts},
        {"nominal_distance", l->nominal_distance ? json_value(*l->nominal_distance) : Json()}};
  }
  if (!r.centered.empty()) {
    Json& centered = out["centered"] = Json::object();
    for (const auto& [name, mean] : r.centered) centered[name] = json_value(mean);
  }
  if (r.refinement) out["refinement"] = json_value(*r.refinement);
  if (!r.refinement_failure.empty()) out["refinement"] = {{"failure", r.refinement_failure}};
  out["equations"] = identified_equations(r);
  out["engineering"] = engineering_json(r);
  out["moments"] = moments_json(r);
  out["diagnostics"] = diagnostics_json(r);
  return out;
}

std::string format_json(const IdentifyResult& r) { return json_text(json_value(r)); }

}  // namespace momentid
