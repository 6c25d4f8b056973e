// The simulation-error refinement's report, as text and as JSON (docs/cli/refine.md): the
// parameters side by side with their start, the simulation error before and after.

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common/json.hpp"
#include "common/number.hpp"
#include "momentid/json.hpp"
#include "momentid/refine.hpp"

namespace momentid {
namespace {

using Json = nlohmann::ordered_json;

std::string interval_text(double low, double high) {
  return std::isfinite(low) ? "[" + number(low) + ", " + number(high) + "]" : "-";
}

}  // namespace

std::string refinement_text(const RefineResult& r) {
  const std::size_t skipped = *std::max_element(r.skip.begin(), r.skip.end());
  std::string out =
      "simulation-error refinement from " + r.start_from + ": " + std::to_string(r.samples) +
      " errors compared (" + std::to_string(r.parameters.size()) + " parameters) in " +
      std::to_string(r.segments) + " segments of " + std::to_string(r.segment_rows) +
      " rows, each simulated from its own initial state, " + std::to_string(r.substeps) +
      (r.substeps == 1 ? " Runge-Kutta step" : " Runge-Kutta steps") + " per sample" +
      (skipped > 0 ? ", the first " + std::to_string(skipped) + " rows of each run skipped" : "") +
      "\n";
  for (const InputBand& b : r.inputs) {
    out += "input " + b.input + ": ";
    if (b.filtered) {
      out += "white noise of rms " + number(b.noise_rms, "%.3g") +
             " beyond its band, removed by a zero-phase low-pass from " + number(b.edge, "%.3g") +
             " Hz (the band's edge) to " + number(b.cutoff, "%.3g") + " Hz\n";
    } else if (b.noise_rms > 0) {
      out += "white noise of rms " + number(b.noise_rms, "%.3g") +
             " across the whole band, left in the simulation\n";
    } else {
      out += "no white noise\n";
    }
  }
  std::size_t width = 9;
  for (const auto& p : r.parameters) width = std::max(width, p.name.size());
  char line[512];
  std::snprintf(line, sizeof line, "  %-*s  %14s  %-27s  %14s  %12s  %s\n", static_cast<int>(width),
                "parameter", "start", "start's 95% interval", "refined", "std error",
                "95% interval");
  out += line;
  for (const RefinedParameter& p : r.parameters) {
    const ParameterEstimate& q = p.refined;
    std::snprintf(line, sizeof line, "  %-*s  %14s  %-27s  %14s  %12s  %s%s\n",
                  static_cast<int>(width), p.name.c_str(), number(p.start).c_str(),
                  interval_text(p.start_low, p.start_high).c_str(), number(q.estimate).c_str(),
                  number(q.std_error, "%.3g").c_str(),
                  q.identifiable ? interval_text(q.ci_low, q.ci_high).c_str() : "not determined",
                  p.moved ? "  <- moved beyond the start's interval" : "");
    out += line;
  }
  out += "simulation error (rms):";
  for (std::size_t o = 0; o < r.outputs.size(); ++o) {
    out += std::string(o ? "," : "") + " " + r.outputs[o].name + " " +
           number(r.outputs[o].rms_start, "%.4g") + " at the start, " +
           number(r.outputs[o].rms, "%.4g") + " refined";
  }
  if (r.noise_replicates > 0) {
    out +=
        "\ninputs' noise (errors in variables): its bias removed from the refined values, "
        "measured as the shift when the noise is doubled (" +
        std::to_string(r.noise_replicates) + " replicates):";
    for (const RefinedParameter& p : r.parameters) {
      out += " " + p.name + " " + number(p.noise_shift, "%.3g");
    }
  }
  out += "\nsearch: " + std::to_string(r.iterations) + " iterations, cost " +
         number(r.cost_start, "%.6g") + " to " + number(r.cost, "%.6g") + ", " +
         (r.converged ? "converged" : "did not converge") + " (" + r.solver + ")\n";
  out += "intervals: t on " + number(r.dof, "%.0f") +
         " degrees of freedom, from the spread of the segments' scores\n";
  return out;
}

std::string format_text(const RefineResult& r) {
  std::string out = "refine " + r.model->name() + " on " + r.data_name + "\n" + refinement_text(r);
  out += "status: " + std::string(r.warnings.empty() ? "ok" : "doubtful") + "\n";
  for (const std::string& w : r.warnings) out += "warning: " + w + "\n";
  return out;
}

nlohmann::ordered_json json_value(const RefineResult& r) {
  Json parameters = Json::object();
  for (const RefinedParameter& p : r.parameters) {
    const ParameterEstimate& q = p.refined;
    parameters[p.name] = {{"start", json_value(p.start)},
                          {"start_std_error", json_value(p.start_error)},
                          {"start_ci95", {json_value(p.start_low), json_value(p.start_high)}},
                          {"estimate", json_value(q.estimate)},
                          {"std_error", json_value(q.std_error)},
                          {"ci95", {json_value(q.ci_low), json_value(q.ci_high)}},
                          {"identifiable", q.identifiable},
                          {"noise_shift", json_value(p.noise_shift)},
                          {"moved", p.moved}};
  }
  Json outputs = Json::object();
  for (const RefinedOutput& o : r.outputs) {
    outputs[o.name] = {{"rms_start", json_value(o.rms_start)}, {"rms", json_value(o.rms)}};
  }
  Json inputs = Json::object();
  for (const InputBand& b : r.inputs) {
    inputs[b.input] = {{"noise_rms", json_value(b.noise_rms)},
                       {"filtered", b.filtered},
                       {"edge_hz", json_value(b.edge)},
                       {"cutoff_hz", json_value(b.cutoff)}};
  }
  return {{"model", r.model->name()},
          {"data", r.data_name},
          {"start_from", r.start_from},
          {"parameters", parameters},
          {"covariance", json_value(r.covariance)},
          {"outputs", outputs},
          {"inputs", inputs},
          {"noise_replicates", r.noise_replicates},
          {"samples", r.samples},
          {"skip", r.skip},
          {"segments", r.segments},
          {"segment_rows", r.segment_rows},
          {"substeps", r.substeps},
          {"cost_start", json_value(r.cost_start)},
          {"cost", json_value(r.cost)},
          {"iterations", r.iterations},
          {"converged", r.converged},
          {"solver", r.solver},
          {"dof", json_value(r.dof)},
          {"status", r.warnings.empty() ? "ok" : "doubtful"},
          {"warnings", r.warnings}};
}

std::string format_json(const RefineResult& r) { return json_text(json_value(r)); }

}  // namespace momentid
