// The zero-lag check of a lagged estimate (docs/measured-data.md, "The zero-lag check"): the
// zero-lag equations of a higher degree, noise-corrected, solved from the same pass, and their
// estimate compared with the lagged one.

#include "app/identify/zero_lag_check.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <set>

#include "app/identify/end_values.hpp"
#include "app/identify/plan.hpp"
#include "solve/distributions.hpp"
#include "solve/long_run.hpp"
#include "solve/rows.hpp"

namespace momentid {
namespace {

// The highest degree of the multipliers, and the most zero-lag equations the check takes. Degree
// 5 reaches E[v^5 (...)], where a law of damping shows that the lagged instruments (up to v^3)
// cannot tell from a cubic one: quadratic drag and cubic damping differ only from the fifth
// Hermite order of v on. Degree 6 adds little power, and moments up to E[v^9] whose few extreme
// batches made the comparison reject true models (2 of 40 records at 1%).
constexpr int kCheckDegree = 5;
constexpr std::size_t kCheckEquations = 32;
// The groups of consecutive batches whose means give the difference's covariance
// (grouped_covariance): 50 groups of 2 s on a record of 10^5 samples at 1 kHz, long enough to
// hold the correlation between neighbouring batches.
constexpr Eigen::Index kGroups = 50;

// The zero-lag system at `degree`, with the rates of change E[(g)'] kept: each batch's own, read
// as increments, take the part of its errors that telescopes out of the batch series (which
// would otherwise swamp the batch covariance that the weighting inverts); the record's are its
// own increments, so that the equations hold on the record as it is, its ends included.
MomentSystem check_system(const Model& model, int degree) {
  DeriveOptions derive_options;
  derive_options.degree = degree;
  derive_options.rates = true;
  return derive(model, derive_options);
}

// The zero-lag equations of `system` over the moments at `index`, each moment by its
// noise-corrected terms (rates as they are).
MomentRows corrected_rows(const Model& model, const MomentSystem& system,
                          const std::map<Monomial, std::size_t>& index,
                          const std::vector<double>& noise) {
  const std::vector<Monomial> needed = moments_to_estimate(system);
  const MomentRows rows = moment_rows(system, positions(needed));
  // The channels inside an abs or sign factor are left uncorrected, as in the lagged equations:
  // what is left is a bias of the order of the noise's variance relative to the channel's
  // (E[sign(v + e) | v] differs from sign(v) only within a few noise deviations of 0), 4e-4 of
  // the moment at 2% noise, 2.5e-3 at 5%, far below the check's sampling errors.
  std::vector<int> variable(model.variables().size());
  std::iota(variable.begin(), variable.end(), 0);
  const std::vector<std::vector<std::size_t>> from = computed_from(model, variable);
  const auto corrected = [&](const MomentRows::Entry& entry) {
    MomentRows::Entry out{.constant = entry.constant, .moments = {}};
    for (const auto& [k, w] : entry.moments) {
      if (needed[k].rate()) {
        out.moments.emplace_back(index.at(needed[k]), w);
        continue;
      }
      for (const auto& [term, weight] :
           noise_corrected(needed[k], correctable_noise(needed[k], noise, from))) {
        if (term.degree() == 0) {
          out.constant += w * weight;
        } else {
          out.moments.emplace_back(index.at(term), w * weight);
        }
      }
    }
    return out;
  };
  MomentRows out;
  for (std::size_t i = 0; i < rows.a.size(); ++i) {
    std::vector<MomentRows::Entry> a;
    for (const MomentRows::Entry& entry : rows.a[i]) a.push_back(corrected(entry));
    out.a.push_back(std::move(a));
    out.b.push_back(corrected(rows.b[i]));
  }
  return out;
}

// The difference of two estimates over the same batches, with Hotelling's test on the
// covariance of its batch series from kGroups groups: the parameters free and identifiable in
// both.
void compare(IdentifyResult::Lagged::ZeroLagCheck& check, const Estimate& lagged,
             const Estimate& zero_lag) {
  const std::vector<ParameterEstimate>& a = lagged.main().parameters;
  const std::vector<ParameterEstimate>& b = zero_lag.main().parameters;
  std::vector<std::size_t> compared;
  for (std::size_t p = 0; p < a.size(); ++p) {
    check.estimates.push_back(b[p].estimate);
    if (!a[p].fixed && a[p].identifiable && b[p].identifiable) compared.push_back(p);
  }
  const std::size_t batches = lagged.error_batches.size();
  const auto groups = std::min<Eigen::Index>(kGroups, static_cast<Eigen::Index>(batches));
  const auto q = static_cast<Eigen::Index>(compared.size());
  if (zero_lag.error_batches.size() != batches || groups < q + 2 || q == 0) {
    check.unavailable =
        "the record's " + std::to_string(batches) + " batches are too few to compare the estimates";
    return;
  }
  Eigen::MatrixXd series(static_cast<Eigen::Index>(batches), q);
  Eigen::VectorXd difference(q);
  for (Eigen::Index i = 0; i < q; ++i) {
    const std::size_t p = compared[static_cast<std::size_t>(i)];
    difference(i) = b[p].estimate - a[p].estimate;
    for (std::size_t k = 0; k < batches; ++k) {
      series(static_cast<Eigen::Index>(k), i) =
          zero_lag.error_batches[k][p] - lagged.error_batches[k][p];
    }
  }
  const Eigen::MatrixXd covariance = grouped_covariance(series, groups);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(covariance);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) {
    check.unavailable = "the difference of the estimates shows no sampling error";
    return;
  }
  const double t2 = difference.dot(ldlt.solve(difference));
  const auto k = static_cast<double>(groups), d = static_cast<double>(q);
  check.statistic = t2;
  check.dof = {d, k - d};
  check.pvalue = f_upper_tail((k - d) / (d * (k - 1)) * t2, d, k - d);
}

}  // namespace

std::optional<ZeroLagCheckPlan> plan_zero_lag_check(const Model& model,
                                                    const IdentifyOptions& options,
                                                    const std::vector<bool>& measured) {
  // Only for the lagged equations the defaults chose for a record with every state measured.
  if (options.method != Method::kAuto || options.lags || options.instruments ||
      !options.integrate.empty() || options.weighting == Weighting::kLeastSquares ||
      !model.measured_derivatives().empty()) {
    return std::nullopt;
  }
  for (std::size_t v = 0; v < model.channel_count(); ++v) {
    if (!measured[v]) return std::nullopt;
  }
  ZeroLagCheckPlan plan;
  for (int degree = 1; degree <= kCheckDegree; ++degree) {
    MomentSystem system = check_system(model, degree);
    const std::size_t equations = system.equations.size();
    if (equations > kCheckEquations) {
      if (degree == 1) {
        plan.unavailable = "the zero-lag equations of degree 1 number " +
                           std::to_string(equations) + ", more than the check's " +
                           std::to_string(kCheckEquations);
      }
      break;
    }
    plan.degree = degree;
    plan.system = std::move(system);
  }
  if (plan.degree == 0) return plan;
  // The moments of the highest degree's equations, with the lower powers that their noise
  // correction reads (listed with every state noisy); those of a lower degree are among them.
  std::vector<double> noisy(model.variables().size(), 0.0);
  for (std::size_t v = 0; v < noisy.size(); ++v) {
    if (model.variables()[v].kind == VariableKind::kState) noisy[v] = 1;
  }
  std::set<Monomial> seen;
  for (const Monomial& m : moments_to_estimate(*plan.system)) {
    if (m.rate()) {
      if (seen.insert(m).second) plan.moments.push_back(m);
      continue;
    }
    for (const auto& [term, weight] : noise_corrected(m, noisy)) {
      if (term.degree() != 0 && seen.insert(term).second) plan.moments.push_back(term);
    }
  }
  return plan;
}

void check_with_zero_lag(IdentifyResult& result, const ZeroLagCheckPlan& plan,
                         const MomentEstimates& moments, const std::vector<int>& channel,
                         const std::vector<std::optional<double>>& fixed) {
  const Model& model = *result.model;
  // Assigned, not emplaced: clang cannot yet construct a nested class with default member
  // initializers in place.
  result.lagged->zero_lag_check = IdentifyResult::Lagged::ZeroLagCheck{};
  IdentifyResult::Lagged::ZeroLagCheck& check = *result.lagged->zero_lag_check;
  if (!plan.unavailable.empty()) {
    check.unavailable = plan.unavailable;
    return;
  }
  if (result.data.hold == InputHold::kZeroOrderHold) {
    check.unavailable =
        "the input is held over each sample, whose kinks the zero-lag equations would need "
        "corrected";
    return;
  }
  // The noise on each model variable, as the lagged equations took it.
  std::vector<double> noise(model.variables().size(), 0.0);
  for (std::size_t v = 0; v < noise.size(); ++v) {
    const int c = channel[v];
    if (c >= 0 && static_cast<std::size_t>(c) < result.lagged->noise.size()) {
      noise[v] = result.lagged->noise[static_cast<std::size_t>(c)];
    }
  }
  // The highest degree whose equations have their kBatchesPerEquation batches each.
  const std::size_t batches = moments.batch_means.size();
  int degree = plan.degree;
  const MomentSystem* system = &*plan.system;
  std::optional<MomentSystem> lower;
  while (degree > 1 && kBatchesPerEquation * system->equations.size() > batches) {
    system = &lower.emplace(check_system(model, --degree));
  }
  if (kBatchesPerEquation * system->equations.size() > batches) {
    check.unavailable = "the record's " + std::to_string(batches) +
                        " batches are too few for the zero-lag equations (" +
                        std::to_string(kBatchesPerEquation) + " per equation)";
    return;
  }
  std::map<Monomial, std::size_t> index;
  for (std::size_t k = 0; k < plan.moments.size(); ++k) index.emplace(plan.moments[k], k);
  MomentEstimates estimates = moments;
  increments_to_rates(plan.moments, result.data.time_step, estimates);
  const MomentRows rows = corrected_rows(model, *system, index, noise);
  check.degree = degree;
  check.equations = rows.a.size();
  std::vector<std::string> names;
  for (const Declaration& p : model.parameters()) names.push_back(p.name);
  const Estimate zero_lag = solve_rows(rows, names, estimates,
                                       {.gmm = rows.a.size() > names.size(),
                                        .fixed = fixed,
                                        .normalise_rows = true,
                                        .moment_variance = {}});
  if (zero_lag.status != Status::kOk) {
    check.unavailable = "the zero-lag equations give no estimate: " + zero_lag.message;
    return;
  }
  compare(check, result.estimate, zero_lag);
}

}  // namespace momentid
