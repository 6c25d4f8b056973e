#include "momentid/identify.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/json.hpp"

namespace momentid {

void IdentifyOptions::validate(const Model& model) const {
  if (batches < kMinBatches || batches > kMaxBatches) {
    throw UsageError("batches: expected a number from " + std::to_string(kMinBatches) + " to " +
                     std::to_string(kMaxBatches) + ", found " + std::to_string(batches));
  }
  if (degree < 0 || degree > kMaxDegree) {
    throw UsageError("degree: expected 0 (automatic) or a number from 1 to " +
                     std::to_string(kMaxDegree) + ", found " + std::to_string(degree));
  }
  if (input_shift < -kMaxInputShift || input_shift > kMaxInputShift) {
    throw UsageError("input shift: expected a number from -" + std::to_string(kMaxInputShift) +
                     " to " + std::to_string(kMaxInputShift) + ", found " +
                     std::to_string(input_shift));
  }
  const auto& variables = model.variables();
  for (const auto& column : columns) {
    if (std::find(variables.begin(), variables.end(), column.first) == variables.end()) {
      throw UsageError("--columns: '" + column.first + "' is not a state or input of model " +
                       model.name());
    }
  }
}

const std::vector<ParameterEstimate>& IdentifyResult::parameters() const {
  return gmm && !estimate.gmm_parameters.empty() ? estimate.gmm_parameters : estimate.parameters;
}

IdentifyResult identify(const Model& model, const DataSource& source,
                        const IdentifyOptions& options) {
  options.validate(model);
  IdentifyResult result;
  result.model = std::make_shared<const Model>(model);
  result.data_name = source.name();
  result.gmm = options.gmm;
  DeriveOptions derive_options;
  derive_options.multipliers = options.multipliers;
  derive_options.degree = options.degree;
  result.system = derive(*result.model, derive_options);
  result.moments = moments_to_estimate(result.system);

  DataOptions data_options;
  data_options.hold = options.hold;
  data_options.batches = options.batches;
  data_options.rename = options.columns;
  data_options.min_rows = 2 * options.batches;
  data_options.input_shift = options.input_shift;
  std::vector<std::string> states, inputs;
  for (const auto& d : model.states()) states.push_back(d.name);
  for (const auto& d : model.inputs()) inputs.push_back(d.name);
  result.data = moments_from_data(source, states, inputs, result.moments, data_options);
  result.estimate = solve(result.system, result.data.estimates, {.gmm = options.gmm});
  return result;
}

std::vector<std::string> warnings(const IdentifyResult& r) {
  std::vector<std::string> w = smoothness_warnings(r.data);
  if (r.estimate.status != Estimate::Status::kOk) w.insert(w.begin(), r.estimate.message);
  w.insert(w.end(), r.estimate.warnings.begin(), r.estimate.warnings.end());
  return w;
}

namespace {

std::string number(double x, const char* format = "%.6g") {
  if (std::isnan(x)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

std::string json_number(double x) {
  if (!std::isfinite(x)) return "null";
  char text[64];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

const char* hold_name(InputHold hold) {
  return hold == InputHold::kZeroOrderHold ? "zoh" : "sample";
}

void table(std::ostringstream& out, const std::vector<ParameterEstimate>& parameters) {
  std::size_t width = 9;
  for (const auto& p : parameters) width = std::max(width, p.name.size());
  char line[256];
  std::snprintf(line, sizeof line, "  %-*s  %14s  %12s  %s\n", static_cast<int>(width), "parameter",
                "estimate", "std error", "95% interval");
  out << line;
  for (const auto& p : parameters) {
    const std::string interval = p.identifiable
                                     ? "[" + number(p.ci_low) + ", " + number(p.ci_high) + "]"
                                     : "not identifiable";
    std::snprintf(line, sizeof line, "  %-*s  %14s  %12s  %s\n", static_cast<int>(width),
                  p.name.c_str(), number(p.estimate).c_str(), number(p.std_error, "%.3g").c_str(),
                  interval.c_str());
    out << line;
  }
}

}  // namespace

std::string format_text(const IdentifyResult& r) {
  const Estimate& e = r.estimate;
  const DataMoments& d = r.data;
  std::ostringstream out;
  out << "model " << r.model->name() << ", data " << r.data_name << ": " << d.rows << " rows in "
      << d.runs << (d.runs == 1 ? " run" : " runs");
  if (d.time_step) out << ", dt = " << number(*d.time_step);
  out << ", input hold " << hold_name(d.hold) << "\n\n";
  if (r.gmm && !e.gmm_parameters.empty()) {
    out << "optimally weighted estimate (two-step GMM)\n";
    table(out, e.gmm_parameters);
    out << "\nleast-squares estimate (first step)\n";
  } else {
    out << "least-squares estimate\n";
  }
  table(out, e.parameters);
  out << "\ndiagnostics\n";
  out << "  equations: " << e.rows << ", rank " << e.rank << " of " << e.parameters.size()
      << ", condition number " << number(e.condition, "%.3g") << "\n";
  out << "  batches: " << e.batches << " (standard errors from the spread of batch means)\n";
  if (e.j_statistic) {
    out << "  J test: J = " << number(*e.j_statistic, "%.4g") << " on " << e.j_dof
        << " degrees of freedom, p = " << number(*e.j_pvalue, "%.3g")
        << (*e.j_pvalue < 0.01 ? " (the model does not fit the data)" : "") << "\n";
  }
  if (!e.identities.empty()) {
    out << "  stationarity identities (sample violation, z-score):\n";
    for (const IdentityCheck& c : e.identities) {
      out << "    " << c.identity << ": " << number(c.violation, "%.3g")
          << " (z = " << number(c.z, "%.2f") << ")\n";
    }
  }
  const std::vector<std::string> all = warnings(r);
  if (all.empty()) out << "  warnings: none\n";
  for (const std::string& w : all) out << "  warning: " << w << "\n";
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
             "], \"identifiable\": " + (p.identifiable ? "true" : "false") + "}";
    }
    return out + "\n  }";
  };
  const bool gmm = r.gmm && !e.gmm_parameters.empty();
  std::ostringstream out;
  out << "{\n  \"model\": " << json_string(r.model->name())
      << ",\n  \"data\": " << json_string(r.data_name)
      << ",\n  \"parameters\": " << parameters(gmm ? e.gmm_parameters : e.parameters);
  if (gmm) out << ",\n  \"least_squares\": " << parameters(e.parameters);
  out << ",\n  \"moments\": {";
  for (std::size_t k = 0; k < r.moments.size(); ++k) {
    out << (k ? ", " : "") << json_string(format_moment(*r.model, r.moments[k])) << ": "
        << json_number(d.estimates.mean[k]);
  }
  out << "}";
  out << ",\n  \"diagnostics\": {\n    \"status\": "
      << json_string(e.status == Estimate::Status::kOk              ? "ok"
                     : e.status == Estimate::Status::kRankDeficient ? "rank-deficient"
                                                                    : "nothing-identifiable")
      << ",\n    \"rows\": " << e.rows << ",\n    \"rank\": " << e.rank
      << ",\n    \"condition\": " << json_number(e.condition) << ",\n    \"batches\": " << e.batches
      << ",\n    \"samples\": " << d.rows << ",\n    \"runs\": " << d.runs
      << ",\n    \"input_hold\": " << json_string(hold_name(d.hold))
      << ",\n    \"j_statistic\": " << (e.j_statistic ? json_number(*e.j_statistic) : "null")
      << ",\n    \"j_dof\": " << e.j_dof
      << ",\n    \"j_pvalue\": " << (e.j_pvalue ? json_number(*e.j_pvalue) : "null")
      << ",\n    \"identities\": [";
  for (std::size_t i = 0; i < e.identities.size(); ++i) {
    const IdentityCheck& c = e.identities[i];
    out << (i ? ", " : "") << "{\"identity\": " << json_string(c.identity)
        << ", \"violation\": " << json_number(c.violation) << ", \"z\": " << json_number(c.z)
        << "}";
  }
  out << "],\n    \"warnings\": [";
  const std::vector<std::string> all = warnings(r);
  for (std::size_t i = 0; i < all.size(); ++i) {
    out << (i ? ", " : "") << json_string(all[i]);
  }
  out << "]\n  }\n}\n";
  return out.str();
}

}  // namespace momentid
