#include "momentid/estimate.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "solve/distributions.hpp"
#include "solve/long_run.hpp"

namespace momentid {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// d A / d mu_k and d b / d mu_k: which entries of the system a moment enters, with its weight.
struct MomentUse {
  std::vector<std::tuple<Eigen::Index, Eigen::Index, double>> a;  // row, parameter, weight
  std::vector<std::pair<Eigen::Index, double>> b;                 // row, weight
};

std::string format_number(double x) {
  std::ostringstream out;
  out.precision(4);
  out << x;
  return out.str();
}

}  // namespace

std::vector<Monomial> moments_to_estimate(const MomentSystem& system) {
  std::vector<Monomial> out = system.moments;
  std::set<Monomial, MomentOrder> seen(out.begin(), out.end());
  const Monomial one(system.model->variables().size(), 0);
  auto add = [&](const Monomial& m) {
    if (m != one && seen.insert(m).second) out.push_back(m);
  };
  for (const DataIdentity& id : system.identities) {
    add(id.moment);
    for (const auto& [m, w] : id.value) add(m);
  }
  return out;
}

namespace {

// Row b: n_b / n (mu_b - mu) for batch b of n_b intervals (n their average) and the record's means
// mu: the batch series that long_run_covariance expects.
MatrixXd batch_deviations(const MomentEstimates& estimates) {
  const auto b = static_cast<Eigen::Index>(estimates.batch_means.size());
  const auto k = static_cast<Eigen::Index>(estimates.mean.size());
  MatrixXd means(b, k);
  VectorXd length = VectorXd::Ones(b);
  for (Eigen::Index i = 0; i < b; ++i) {
    const auto row = static_cast<std::size_t>(i);
    for (Eigen::Index j = 0; j < k; ++j) {
      means(i, j) = estimates.batch_means[row][static_cast<std::size_t>(j)];
    }
    if (!estimates.batch_intervals.empty()) {
      length(i) = static_cast<double>(estimates.batch_intervals[row]);
    }
  }
  if (b == 0) return means;
  length /= length.mean();
  const Eigen::RowVectorXd mean = (length.transpose() * means) / static_cast<double>(b);
  return length.asDiagonal() * (means.rowwise() - mean);
}

// solve_rows with the moments' batch series (batch_deviations) at hand, and a covariance of the
// moments' record means known from elsewhere (`known`, moments x moments; solve: the rates'),
// which is added to the errors.
Estimate solve_on(const MomentRows& system, const std::vector<std::string>& names,
                  const MomentEstimates& estimates, const MatrixXd& deviations,
                  const SolveOptions& options, const MatrixXd& known);

// `series` as rows of `out`, when given.
void store(const MatrixXd& series, std::vector<std::vector<double>>* out) {
  if (out == nullptr) return;
  out->assign(static_cast<std::size_t>(series.rows()), {});
  for (Eigen::Index b = 0; b < series.rows(); ++b) {
    for (Eigen::Index p = 0; p < series.cols(); ++p) {
      (*out)[static_cast<std::size_t>(b)].push_back(series(b, p));
    }
  }
}

// `errors` of a series x = J mu plus the covariance J K J' that a known covariance K of the
// moments adds, with the degrees of freedom of the sum (Satterthwaite, K taken as exact: the
// fewest over the series' components).
LongRunCovariance with_known(LongRunCovariance errors, const MatrixXd& jacobian,
                             const MatrixXd& known) {
  if (known.isZero(0)) return errors;
  const MatrixXd added = jacobian * known * jacobian.transpose();
  double dof = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < added.rows(); ++i) {
    const double series = errors.covariance(i, i), total = series + added(i, i);
    if (series > 0) dof = std::min(dof, errors.dof * (total / series) * (total / series));
  }
  errors.covariance += added;
  if (std::isfinite(dof)) errors.dof = dof;
  return errors;
}

// The warnings that say the standard errors are rough.
void warn_about_errors(Estimate& out, const LongRunCovariance& errors) {
  if (errors.order == 0 && out.batches >= 2) {
    out.warnings.push_back("only " + std::to_string(out.batches) +
                           " batches: the standard errors take the batch means as independent, "
                           "which overstates them for records without noise (use a longer record "
                           "or more batches)");
  } else if (errors.dof < 10) {
    out.warnings.push_back("the standard errors rest on " + format_number(errors.dof) +
                           " degrees of freedom: they are rough (use a longer record)");
  }
}

// check_identities with the batch series at hand.
std::vector<IdentityCheck> identity_checks(const MomentSystem& system,
                                           const std::vector<Monomial>& moments,
                                           const MomentEstimates& estimates,
                                           const MatrixXd& deviations) {
  const Model& model = *system.model;
  const Monomial one(model.variables().size(), 0);
  std::map<Monomial, std::size_t> index;
  for (std::size_t k = 0; k < moments.size(); ++k) index[moments[k]] = k;
  std::vector<IdentityCheck> out;
  for (const DataIdentity& id : system.identities) {
    // Weights over the moments: +1 for E[m], minus the value's weights; E[1] is a constant.
    VectorXd weights = VectorXd::Zero(deviations.cols());
    double constant = 0;
    bool available = index.count(id.moment) != 0;
    if (available) weights(static_cast<Eigen::Index>(index.at(id.moment))) += 1.0;
    for (const auto& [m, w] : id.value) {
      if (m == one) {
        constant += w.to_double();
      } else if (index.count(m) != 0) {
        weights(static_cast<Eigen::Index>(index.at(m))) -= w.to_double();
      } else {
        available = false;
      }
    }
    if (!available) continue;
    IdentityCheck check;
    check.identity = format_moment(model, id.moment) + " = " + format_combination(model, id.value);
    check.violation = -constant;
    for (Eigen::Index i = 0; i < weights.size(); ++i) {
      check.violation += weights(i) * estimates.mean[static_cast<std::size_t>(i)];
    }
    const double variance = long_run_covariance(deviations * weights).covariance(0, 0);
    check.z = variance > 0 ? check.violation / std::sqrt(variance) : kNaN;
    out.push_back(check);
  }
  return out;
}

}  // namespace

std::vector<IdentityCheck> check_identities(const MomentSystem& system,
                                            const std::vector<Monomial>& moments,
                                            const MomentEstimates& estimates) {
  return identity_checks(system, moments, estimates, batch_deviations(estimates));
}

Estimate solve(const MomentSystem& system, const MomentEstimates& estimates,
               const SolveOptions& options) {
  const Model& model = *system.model;
  const std::vector<Monomial> moments = moments_to_estimate(system);
  std::map<Monomial, std::size_t> index;
  for (std::size_t k = 0; k < moments.size(); ++k) index[moments[k]] = k;
  const Monomial one(model.variables().size(), 0);
  const auto entry = [&](const MomentCombination& c) {
    MomentRows::Entry out;
    for (const auto& [m, w] : c) {
      if (m == one) {
        out.constant += w.to_double();
      } else {
        out.moments.emplace_back(index.at(m), w.to_double());
      }
    }
    return out;
  };
  MomentRows rows;
  for (const MomentEquation& eq : system.equations) {
    std::vector<MomentRows::Entry> a;
    for (const MomentCombination& c : eq.coefficients) a.push_back(entry(c));
    rows.a.push_back(std::move(a));
    rows.b.push_back(entry(eq.rhs));
  }
  std::vector<std::string> names;
  for (const Declaration& p : model.parameters()) names.push_back(p.name);
  const MatrixXd deviations = batch_deviations(estimates);
  // The rates at their stationary value; their known covariance over all the moments.
  MomentEstimates at_rest = estimates;
  std::vector<std::size_t> rates;
  for (std::size_t k = 0; k < moments.size(); ++k) {
    if (!rate_of(moments[k], model.variables().size())) continue;
    at_rest.mean[k] = 0;
    rates.push_back(k);
  }
  const auto k = static_cast<Eigen::Index>(moments.size());
  MatrixXd known = MatrixXd::Zero(k, k);
  if (!options.rate_covariance.empty()) {
    if (options.rate_covariance.size() != rates.size()) {
      throw std::invalid_argument("solve: rate_covariance must be square over the system's rates");
    }
    for (std::size_t i = 0; i < rates.size(); ++i) {
      for (std::size_t j = 0; j < rates.size(); ++j) {
        known(static_cast<Eigen::Index>(rates[i]), static_cast<Eigen::Index>(rates[j])) =
            options.rate_covariance[i].at(j);
      }
    }
  }
  Estimate out = solve_on(rows, names, at_rest, deviations, options, known);
  out.identities = identity_checks(system, moments, estimates, deviations);
  return out;
}

namespace {

// cov(i, j) / sqrt(cov(i, i) cov(j, j)), NaN where a variance is not positive or a parameter
// is not identifiable.
std::vector<std::vector<double>> correlation_of(const MatrixXd& cov,
                                                const std::vector<bool>& identifiable) {
  const auto n = static_cast<std::size_t>(cov.rows());
  std::vector<std::vector<double>> out(n, std::vector<double>(n, kNaN));
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      const auto a = static_cast<Eigen::Index>(i), b = static_cast<Eigen::Index>(j);
      const double scale = std::sqrt(cov(a, a) * cov(b, b));
      // Symmetric to the last bit, whatever the rounding of the products that made cov.
      if (identifiable[i] && identifiable[j] && scale > 0) {
        out[i][j] = (cov(a, b) + cov(b, a)) / 2 / scale;
      }
    }
  }
  return out;
}

}  // namespace

namespace {

// The system with the fixed parameters' columns moved to the right-hand side: b - a_p v_p.
MomentRows without_fixed(const MomentRows& system,
                         const std::vector<std::optional<double>>& fixed) {
  MomentRows out;
  for (std::size_t r = 0; r < system.a.size(); ++r) {
    std::vector<MomentRows::Entry> row;
    MomentRows::Entry b = system.b[r];
    for (std::size_t p = 0; p < system.a[r].size(); ++p) {
      const MomentRows::Entry& e = system.a[r][p];
      if (!fixed[p]) {
        row.push_back(e);
        continue;
      }
      b.constant -= *fixed[p] * e.constant;
      for (const auto& [k, w] : e.moments) b.moments.emplace_back(k, -*fixed[p] * w);
    }
    out.a.push_back(std::move(row));
    out.b.push_back(std::move(b));
  }
  return out;
}

// The estimate of the free parameters spread back over all of them: the fixed ones with their
// values, no error and no correlation.
Estimate with_fixed(Estimate free, const std::vector<std::string>& names,
                    const std::vector<std::optional<double>>& fixed) {
  const auto spread = [&](const std::vector<ParameterEstimate>& list) {
    std::vector<ParameterEstimate> out;
    for (std::size_t p = 0, k = 0; p < names.size(); ++p) {
      if (fixed[p]) {
        out.push_back({names[p], *fixed[p], 0, *fixed[p], *fixed[p], true, true});
      } else {
        out.push_back(list[k++]);
      }
    }
    return out;
  };
  const auto spread_matrix = [&](const std::vector<std::vector<double>>& m) {
    std::vector<std::vector<double>> out(names.size(), std::vector<double>(names.size(), kNaN));
    std::vector<std::size_t> index;
    for (std::size_t p = 0; p < names.size(); ++p) {
      if (!fixed[p]) index.push_back(p);
    }
    for (std::size_t i = 0; i < index.size(); ++i) {
      for (std::size_t j = 0; j < index.size(); ++j) out[index[i]][index[j]] = m[i][j];
    }
    return out;
  };
  free.parameters = spread(free.parameters);
  if (!free.gmm_parameters.empty()) free.gmm_parameters = spread(free.gmm_parameters);
  if (!free.correlation.empty()) free.correlation = spread_matrix(free.correlation);
  if (!free.gmm_correlation.empty()) free.gmm_correlation = spread_matrix(free.gmm_correlation);
  return free;
}

}  // namespace

Estimate solve_rows(const MomentRows& system, const std::vector<std::string>& names,
                    const MomentEstimates& estimates, const SolveOptions& options) {
  const auto k = static_cast<Eigen::Index>(estimates.mean.size());
  return solve_on(system, names, estimates, batch_deviations(estimates), options,
                  MatrixXd::Zero(k, k));
}

namespace {

Estimate solve_on(const MomentRows& system, const std::vector<std::string>& names,
                  const MomentEstimates& estimates, const MatrixXd& deviations,
                  const SolveOptions& options, const MatrixXd& known) {
  if (std::any_of(options.fixed.begin(), options.fixed.end(), [](const auto& v) { return v; })) {
    if (options.fixed.size() != names.size()) {
      throw std::invalid_argument("solve_rows: one fixed value or nullopt per parameter needed");
    }
    std::vector<std::string> free_names;
    for (std::size_t p = 0; p < names.size(); ++p) {
      if (!options.fixed[p]) free_names.push_back(names[p]);
    }
    SolveOptions free_options = options;
    free_options.fixed.clear();
    Estimate out = with_fixed(solve_on(without_fixed(system, options.fixed), free_names, estimates,
                                       deviations, free_options, known),
                              names, options.fixed);
    // The fixed parameters have no error: zero columns.
    if (options.error_batches) {
      for (std::vector<double>& row : *options.error_batches) {
        std::vector<double> all;
        for (std::size_t p = 0, k = 0; p < names.size(); ++p) {
          all.push_back(options.fixed[p] ? 0.0 : row[k++]);
        }
        row = std::move(all);
      }
    }
    return out;
  }
  const auto rows = static_cast<Eigen::Index>(system.a.size());
  const auto params = static_cast<Eigen::Index>(names.size());
  const auto k_count = static_cast<Eigen::Index>(estimates.mean.size());

  Estimate out;
  out.rows = system.a.size();
  out.batches = estimates.batch_means.size();
  out.intervals = estimates.intervals;
  for (const std::string& name : names) {
    out.parameters.push_back({name, kNaN, kNaN, kNaN, kNaN, /*identifiable=*/false});
  }
  if (rows == 0 || params == 0) {
    out.status = Estimate::Status::kNothingIdentifiable;
    out.message = "the model gives no moment equations";
    return out;
  }

  VectorXd mu(k_count);
  for (Eigen::Index k = 0; k < k_count; ++k) mu(k) = estimates.mean[static_cast<std::size_t>(k)];

  MatrixXd a = MatrixXd::Zero(rows, params);
  VectorXd b = VectorXd::Zero(rows);
  std::vector<MomentUse> uses(static_cast<std::size_t>(k_count));
  const auto add = [&](const MomentRows::Entry& e, double& into, auto&& use) {
    into += e.constant;
    for (const auto& [k, w] : e.moments) {
      into += w * mu(static_cast<Eigen::Index>(k));
      use(k, w);
    }
  };
  for (Eigen::Index r = 0; r < rows; ++r) {
    const auto& row = system.a[static_cast<std::size_t>(r)];
    for (Eigen::Index p = 0; p < params; ++p) {
      add(row[static_cast<std::size_t>(p)], a(r, p),
          [&](std::size_t k, double w) { uses[k].a.emplace_back(r, p, w); });
    }
    add(system.b[static_cast<std::size_t>(r)], b(r),
        [&](std::size_t k, double w) { uses[k].b.emplace_back(r, w); });
  }

  if (options.normalise_rows) {
    VectorXd weight = VectorXd::Ones(rows);
    for (Eigen::Index r = 0; r < rows; ++r) {
      if (const double norm = a.row(r).norm(); norm > 0) weight(r) = 1 / norm;
    }
    a = weight.asDiagonal() * a;
    b = b.cwiseProduct(weight);
    for (MomentUse& use : uses) {
      for (auto& [r, p, w] : use.a) w *= weight(r);
      for (auto& [r, w] : use.b) w *= weight(r);
    }
  }

  // Columns scaled to unit length: moments of different orders differ by orders of magnitude.
  VectorXd scale(params);
  for (Eigen::Index p = 0; p < params; ++p) {
    const double norm = a.col(p).norm();
    scale(p) = norm > 0 ? norm : 1;
  }
  const MatrixXd as = a * scale.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<MatrixXd> svd(as, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const VectorXd& sigma = svd.singularValues();
  const double tolerance = 1e-10 * (sigma.size() > 0 ? sigma(0) : 0.0);
  Eigen::Index rank = 0;
  for (Eigen::Index i = 0; i < sigma.size(); ++i) rank += sigma(i) > tolerance ? 1 : 0;
  out.rank = static_cast<std::size_t>(rank);
  const Eigen::Index smallest = std::min(rows, params) - 1;
  out.condition =
      sigma(smallest) > 0 ? sigma(0) / sigma(smallest) : std::numeric_limits<double>::infinity();
  if (rank == 0) {
    out.status = Estimate::Status::kNothingIdentifiable;
    out.message = "the moment equations are all zero for these data";
    return out;
  }

  const MatrixXd u = svd.matrixU().leftCols(rank);
  const MatrixXd v = svd.matrixV().leftCols(rank);
  const VectorXd inverse_sigma = sigma.head(rank).cwiseInverse();
  const MatrixXd pinv = v * inverse_sigma.asDiagonal() * u.transpose();  // P x R
  const MatrixXd normal_pinv = v * inverse_sigma.cwiseAbs2().asDiagonal() * v.transpose();
  const VectorXd theta_scaled = pinv * b;
  const VectorXd theta = theta_scaled.cwiseQuotient(scale);
  const VectorXd residual = b - as * theta_scaled;

  // Parameters that the null space touches cannot be told apart from others.
  std::vector<bool> identifiable(static_cast<std::size_t>(params), true);
  if (rank < params) {
    out.status = Estimate::Status::kRankDeficient;
    const MatrixXd null = svd.matrixV().rightCols(params - rank);
    std::string combos;
    for (Eigen::Index j = 0; j < null.cols(); ++j) {
      VectorXd d = null.col(j).cwiseQuotient(scale);
      d /= d.cwiseAbs().maxCoeff();
      std::string combo;
      for (Eigen::Index p = 0; p < params; ++p) {
        if (std::abs(null(p, j)) < 1e-6) continue;
        identifiable[static_cast<std::size_t>(p)] = false;
        const double w = d(p);
        combo += (combo.empty() ? (w < 0 ? "-" : "") : (w < 0 ? " - " : " + ")) +
                 (std::abs(std::abs(w) - 1) < 1e-9 ? "" : format_number(std::abs(w)) + "*") +
                 names[static_cast<std::size_t>(p)];
      }
      combos += (combos.empty() ? "" : "; ") + combo;
    }
    out.message = "the data cannot separate the parameters along " + combos + ": only " +
                  std::to_string(rank) + " of " + std::to_string(params) +
                  " parameter combinations are determined";
  }

  // The sensitivity d theta / d mu_k of theta = N^-1 A' W b for every moment, with N^-1 =
  // `normal_inverse`, `left` = N^-1 A' W and `weighted_residual` = W (b - A theta), all in
  // scaled columns; unscaled on return.
  const auto sensitivity = [&](const MatrixXd& normal_inverse, const MatrixXd& left,
                               const VectorXd& weighted_residual, const VectorXd& at) {
    MatrixXd jacobian = MatrixXd::Zero(params, k_count);
    for (Eigen::Index k = 0; k < k_count; ++k) {
      const MomentUse& use = uses[static_cast<std::size_t>(k)];
      if (use.a.empty() && use.b.empty()) continue;
      MatrixXd da = MatrixXd::Zero(rows, params);
      VectorXd db = VectorXd::Zero(rows);
      for (const auto& [r, p, w] : use.a) da(r, p) += w / scale(p);
      for (const auto& [r, w] : use.b) db(r) += w;
      jacobian.col(k) =
          (normal_inverse * (da.transpose() * weighted_residual) + left * (db - da * at))
              .cwiseQuotient(scale);
    }
    return jacobian;
  };
  // The errors: the long-run covariance of the parameters' batch series (delta method).
  const MatrixXd ls_jacobian = sensitivity(normal_pinv, pinv, residual, theta_scaled);
  const MatrixXd ls_series = deviations * ls_jacobian.transpose();
  const LongRunCovariance ls_errors =
      with_known(long_run_covariance(ls_series), ls_jacobian, known);
  store(ls_series, options.error_batches);
  out.dof = ls_errors.dof;
  const double t975 = out.batches >= 2 ? ls_errors.t975() : kNaN;
  for (Eigen::Index p = 0; p < params; ++p) {
    ParameterEstimate& e = out.parameters[static_cast<std::size_t>(p)];
    e.estimate = theta(p);
    e.identifiable = identifiable[static_cast<std::size_t>(p)];
    e.std_error = e.identifiable && out.batches >= 2
                      ? std::sqrt(std::max(0.0, ls_errors.covariance(p, p)))
                      : kNaN;
    e.ci_low = e.estimate - t975 * e.std_error;
    e.ci_high = e.estimate + t975 * e.std_error;
  }
  if (out.batches >= 2) out.correlation = correlation_of(ls_errors.covariance, identifiable);
  warn_about_errors(out, ls_errors);
  if (out.condition > 1e8) {
    out.warnings.push_back("the equations are ill-conditioned (condition number " +
                           format_number(out.condition) +
                           "): the parameters are nearly inseparable with these multipliers");
  }

  if (!options.gmm) return out;
  // Two-step weighting: the equations g = A theta - b weighted by the inverse of their batch
  // covariance S / B at the first-step estimate (batch_covariance: many degrees of freedom; for
  // equations without noise too large by a common factor, which the weights do not feel). The
  // estimate's errors and the J test come from the long-run covariance, not from S.
  if (rank < params) {
    out.warnings.push_back("no optimally weighted estimate: the system is rank-deficient");
    return out;
  }
  // S has rank B - 1 at most: with as many equations or more it is singular and the weighting
  // meaningless.
  if (out.batches < system.a.size() + 2) {
    out.warnings.push_back(
        "no optimally weighted estimate: it needs more batches than equations (" +
        std::to_string(out.batches) + " batches for " + std::to_string(rows) +
        " equations): use --batches");
    return out;
  }
  // dg / dmu at theta.
  const auto equations_of = [&](const VectorXd& at) {
    MatrixXd g_mu = MatrixXd::Zero(rows, k_count);
    for (Eigen::Index k = 0; k < k_count; ++k) {
      const MomentUse& use = uses[static_cast<std::size_t>(k)];
      for (const auto& [r, p, w] : use.a) g_mu(r, k) += w * at(p);
      for (const auto& [r, w] : use.b) g_mu(r, k) -= w;
    }
    return g_mu;
  };
  const MatrixXd g_mu = equations_of(theta);
  const MatrixXd s =
      batch_covariance(deviations * g_mu.transpose()) + g_mu * known * g_mu.transpose();
  Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(s);
  const VectorXd lambda = eigen.eigenvalues();
  const double lambda_max = lambda.maxCoeff();
  VectorXd inverse_lambda = VectorXd::Zero(rows);
  Eigen::Index s_rank = 0;
  for (Eigen::Index i = 0; i < rows; ++i) {
    if (lambda(i) > 1e-12 * lambda_max) {
      inverse_lambda(i) = 1 / lambda(i);
      ++s_rank;
    }
  }
  const MatrixXd w =
      eigen.eigenvectors() * inverse_lambda.asDiagonal() * eigen.eigenvectors().transpose();
  const MatrixXd information = as.transpose() * w * as;
  const MatrixXd information_inverse = information.ldlt().solve(MatrixXd::Identity(params, params));
  const MatrixXd gmm_left = information_inverse * as.transpose() * w;
  const VectorXd theta_gmm_scaled = gmm_left * b;
  const VectorXd theta_gmm = theta_gmm_scaled.cwiseQuotient(scale);
  const VectorXd gmm_residual = b - as * theta_gmm_scaled;
  // The weights come from the same batches as the errors, which makes the batch series of the
  // estimate's errors look too small by (n - m + q) / n and the estimate less efficient than with
  // known weights by (n - 1) / (n - m + q - 1), for n = B - 1 degrees of freedom of S, m
  // equations and q parameters (Gaussian batch means, Wishart S): both factors are undone.
  const auto n = static_cast<double>(out.batches - 1);
  const auto m = static_cast<double>(s_rank);
  const auto q = static_cast<double>(params);
  const double finite_sample = n * (n - 1) / ((n - m + q) * (n - m + q - 1));
  const MatrixXd gmm_jacobian =
      sensitivity(information_inverse, gmm_left, w * gmm_residual, theta_gmm_scaled);
  const MatrixXd gmm_series = std::sqrt(finite_sample) * deviations * gmm_jacobian.transpose();
  const LongRunCovariance gmm_errors =
      with_known(long_run_covariance(gmm_series), gmm_jacobian, known);
  store(gmm_series, options.error_batches);
  out.gmm_dof = gmm_errors.dof;
  const double gmm_t975 = gmm_errors.t975();
  for (Eigen::Index p = 0; p < params; ++p) {
    ParameterEstimate e{names[static_cast<std::size_t>(p)]};
    e.estimate = theta_gmm(p);
    e.std_error = std::sqrt(std::max(0.0, gmm_errors.covariance(p, p)));
    e.ci_low = e.estimate - gmm_t975 * e.std_error;
    e.ci_high = e.estimate + gmm_t975 * e.std_error;
    out.gmm_parameters.push_back(e);
  }
  out.gmm_correlation = correlation_of(gmm_errors.covariance, identifiable);

  // The J test. The residual g = A theta - b lies in the d = m - q directions that the estimate
  // leaves free, with covariance V there: the long-run covariance of the batch series of
  // M g(mu_b), M = I - A N^-1 A' W. J = g' W g is then a weighted sum of chi-square variables,
  // with weights the eigenvalues of W V, which a scaled chi-square matches in mean and variance
  // (Satterthwaite): J / c ~ chi-square(k), c k = tr(W V), c^2 k = tr((W V)^2), the latter less
  // the excess that the noise of V, on nu degrees of freedom, adds to it as it does to a Wishart
  // matrix: E tr((W V^)^2) = (1 + 1/nu) tr((W V)^2) + tr(W V)^2 / nu. The scale comes from V:
  // J / (c k) ~ F(k, nu'), where tr(W V) sums k components of nu degrees of freedom each (nu
  // counts those of one standardised series). W from the same batches makes J Hotelling's T^2
  // rather than a chi-square: J (n - d + 1) / n over its scale is F(d, n - d + 1), so the
  // denominator's relative variances add, 1 / nu' = 1 / (n - d + 1) + 1 / (k nu). (With W from
  // few batches, n not far above d, the test is conservative: tr(W V) is then biased upwards,
  // W being fitted to the batches that V also sees.) Reported:
  // J d / tr(W V), whose mean is d for the right model whether the equations telescope (W too
  // small by a factor near B) or not.
  out.j_dof = static_cast<int>(s_rank - params);
  if (out.j_dof <= 0) {
    out.warnings.push_back("no J test: as many equations as parameters (add multipliers)");
    return out;
  }
  const auto d = static_cast<double>(out.j_dof);
  const MatrixXd free_part = MatrixXd::Identity(rows, rows) - as * gmm_left;
  const MatrixXd free_mu = free_part * equations_of(theta_gmm);
  const LongRunCovariance residual_errors =
      with_known(long_run_covariance(deviations * free_mu.transpose()), free_mu, known);
  const MatrixXd wv = w * residual_errors.covariance;
  const double nu = residual_errors.dof, trace = wv.trace();
  const double trace_square =
      std::max(((wv * wv).trace() - trace * trace / nu) / (1 + 1 / nu), trace * trace / out.j_dof);
  if (!(trace > 0 && trace_square > 0)) {
    out.warnings.push_back("no J test: the residuals show no sampling error");
    out.j_dof = 0;
    return out;
  }
  const double j = gmm_residual.dot(w * gmm_residual);
  const double k = trace * trace / trace_square;
  out.j_statistic = j * out.j_dof / trace;
  out.j_pvalue = f_upper_tail(j / trace * (n - d + 1) / n, k,
                              std::max(1.0, 1 / (1 / (n - d + 1) + 1 / (k * nu))));
  return out;
}

}  // namespace

}  // namespace momentid
