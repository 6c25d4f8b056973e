// The held-input correction of the zero-lag estimate: an input held over each sample puts kinks
// into the states at the samples, which bias the moments whose derivative holds it.

#include "app/identify/held_input.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "app/identify/moment_lists.hpp"

namespace momentid {

std::vector<Monomial> second_derivative_moments(const HeldInputCorrections& held) {
  std::vector<Monomial> out;
  for (const HeldInputCorrection& c : held.moments) {
    for (const auto& [m, weight] : c.second_derivative) out.push_back(m);
  }
  return out;
}

namespace {

// The weight `weight` of a moment in E[g''] at the parameters `values`, times `scale`; NaN where
// it cannot be evaluated (e.g. a division by a parameter estimated as 0).
double weight_at(const GiNaC::ex& weight, const GiNaC::exmap& values, double scale) {
  try {
    const GiNaC::ex value = weight.subs(values).evalf();
    if (GiNaC::is_a<GiNaC::numeric>(value)) {
      return scale * GiNaC::ex_to<GiNaC::numeric>(value).to_double();
    }
  } catch (const std::exception&) {
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// The first `count` moments of `all` (indexed by `index`) corrected by -scale E[g''] with the
// weights at the parameters `theta`; nullopt when a weight cannot be evaluated there.
std::optional<MomentEstimates> corrected_moments(const Model& model,
                                                 const HeldInputCorrections& held,
                                                 const std::map<Monomial, std::size_t>& index,
                                                 const MomentEstimates& all, std::size_t count,
                                                 const std::vector<double>& theta, double scale) {
  GiNaC::exmap values;
  for (std::size_t p = 0; p < theta.size(); ++p) {
    values[model.parameter_symbol(static_cast<int>(p))] = theta[p];
  }
  MomentEstimates corrected = first_moments(all, count);
  for (const HeldInputCorrection& c : held.moments) {
    const std::size_t target = index.at(c.moment);
    for (const auto& [m, weight] : c.second_derivative) {
      const double w = weight_at(weight, values, scale);
      if (!std::isfinite(w)) return std::nullopt;
      const auto source = index.find(m);
      if (source == index.end()) {  // the constant 1
        corrected.mean[target] -= w;
        for (std::vector<double>& batch : corrected.batch_means) batch[target] -= w;
        continue;
      }
      corrected.mean[target] -= w * all.mean[source->second];
      for (std::size_t b = 0; b < corrected.batch_means.size(); ++b) {
        corrected.batch_means[b][target] -= w * all.batch_means[b][source->second];
      }
    }
  }
  return corrected;
}

}  // namespace

void correct_for_held_input(IdentifyResult& result, const HeldInputCorrections& held,
                            const std::vector<Monomial>& moments, const MomentEstimates& all,
                            const SolveOptions& solve_options) {
  if (held.moments.empty() && held.unavailable.empty()) return;  // no moment needs it
  IdentifyResult::ZeroLag::HeldInput& out = result.zero_lag->held_input.emplace();
  if (held.moments.empty()) {
    out.unavailable = held.unavailable;
    return;
  }
  if (!result.data.time_step) {
    out.unavailable = "the data give no sample interval (a 't' column or a dt in the metadata)";
    return;
  }
  std::map<Monomial, std::size_t> index;
  for (std::size_t k = 0; k < moments.size(); ++k) index.emplace(moments[k], k);
  const Model& model = *result.model;
  const double scale = *result.data.time_step * *result.data.time_step / 12;
  std::vector<double> before;
  for (const ParameterEstimate& p : result.parameters()) before.push_back(p.estimate);
  // Where a round cannot be made, the result is the uncorrected one.
  const Estimate uncorrected = result.estimate;
  const MomentEstimates uncorrected_moments = result.data.estimates;
  const auto give_up = [&](const char* reason) {
    out.unavailable = reason;
    result.estimate = uncorrected;
    result.data.estimates = uncorrected_moments;
  };
  std::vector<double> theta = before;
  for (int round = 0; round < 2; ++round) {
    if (result.estimate.status != Status::kOk ||
        std::any_of(theta.begin(), theta.end(), [](double t) { return !std::isfinite(t); })) {
      return give_up("the estimate without it does not determine every parameter");
    }
    std::optional<MomentEstimates> corrected =
        corrected_moments(model, held, index, all, result.zero_lag->moments.size(), theta, scale);
    if (!corrected) return give_up("its weights cannot be evaluated at the estimated parameters");
    result.estimate =
        solve(*result.zero_lag->system, result.zero_lag->moments, *corrected, solve_options);
    result.data.estimates = std::move(*corrected);
    theta.clear();
    for (const ParameterEstimate& p : result.parameters()) theta.push_back(p.estimate);
  }
  for (std::size_t p = 0; p < theta.size(); ++p) out.shift.push_back(theta[p] - before[p]);
}

}  // namespace momentid
