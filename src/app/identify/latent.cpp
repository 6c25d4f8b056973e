// Models with latent states (latent.hpp): the coefficients of the equations without them, and
// the parameters from the coefficients by minimum distance.
//
// With c the coefficients' estimates, V their covariance and f(p) the coefficients as functions
// of the free parameters, the parameters minimise (c - f(p))' W (c - f(p)) for a weight W
// (Coefficients: the inverse of the errors' batch covariance, not V^-1), by Levenberg-Marquardt
// from the model's nominal values, else from starts around them; their covariance is L V L' for
// L = (F' W F)^-1 F' W, F the Jacobian of f there (the delta method), and the residual's
// statistic Q (minimum_distance) is chi-square on coefficients - parameters degrees of freedom
// when the model's restrictions on the coefficients hold.

#include "app/identify/latent.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <random>

#include "app/identify/lagged.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/lagged.hpp"
#include "momentid/latent.hpp"
#include "solve/delta_method.hpp"
#include "solve/distributions.hpp"
#include "solve/long_run.hpp"

namespace momentid {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// An expression of the free parameters p as a function that evaluates it: GiNaC's subs and
// evalf take microseconds a term, and the minimum distance evaluates the coefficients and their
// Jacobian tens of thousands of times (search_distance). Sums, products, numbers, parameters and
// powers are evaluated in doubles; anything else through GiNaC.
using Evaluator = std::function<double(const VectorXd&)>;

Evaluator compile(const GiNaC::ex& e, const std::vector<GiNaC::symbol>& symbols) {
  if (GiNaC::is_a<GiNaC::numeric>(e) && GiNaC::ex_to<GiNaC::numeric>(e).is_real()) {
    const double value = GiNaC::ex_to<GiNaC::numeric>(e).to_double();
    return [value](const VectorXd&) { return value; };
  }
  for (std::size_t k = 0; k < symbols.size(); ++k) {
    if (e.is_equal(symbols[k])) {
      return [k = static_cast<Index>(k)](const VectorXd& p) { return p(k); };
    }
  }
  if (GiNaC::is_a<GiNaC::add>(e) || GiNaC::is_a<GiNaC::mul>(e)) {
    std::vector<Evaluator> terms;
    for (std::size_t i = 0; i < e.nops(); ++i) terms.push_back(compile(e.op(i), symbols));
    if (GiNaC::is_a<GiNaC::add>(e)) {
      return [terms](const VectorXd& p) {
        double sum = 0;
        for (const Evaluator& t : terms) sum += t(p);
        return sum;
      };
    }
    return [terms](const VectorXd& p) {
      double product = 1;
      for (const Evaluator& t : terms) product *= t(p);
      return product;
    };
  }
  if (GiNaC::is_a<GiNaC::power>(e)) {
    Evaluator base = compile(e.op(0), symbols), exponent = compile(e.op(1), symbols);
    return [base, exponent](const VectorXd& p) { return std::pow(base(p), exponent(p)); };
  }
  return [e, symbols](const VectorXd& p) {
    GiNaC::exmap at;
    for (std::size_t k = 0; k < symbols.size(); ++k) at[symbols[k]] = p(static_cast<Index>(k));
    const GiNaC::ex value = e.subs(at).evalf();
    return GiNaC::is_a<GiNaC::numeric>(value) ? GiNaC::ex_to<GiNaC::numeric>(value).to_double()
                                              : kNaN;
  };
}

// The coefficients f(p) and their Jacobian, evaluated at values of the free parameters.
class CoefficientMap {
 public:
  CoefficientMap(const Model& model, const Elimination& e) {
    std::vector<GiNaC::symbol> symbols;
    for (int p : e.parameters) symbols.push_back(model.parameter_symbol(p));
    for (const GiNaC::ex& c : e.coefficients) {
      value_.push_back(compile(c, symbols));
      std::vector<Evaluator> row;
      for (const GiNaC::symbol& s : symbols) row.push_back(compile(c.diff(s), symbols));
      jacobian_.push_back(std::move(row));
    }
    parameters_ = static_cast<Index>(symbols.size());
  }

  Index parameters() const { return parameters_; }
  Index coefficients() const { return static_cast<Index>(value_.size()); }

  VectorXd value(const VectorXd& p) const {
    VectorXd out(coefficients());
    for (Index i = 0; i < out.size(); ++i) out(i) = value_[static_cast<std::size_t>(i)](p);
    return out;
  }

  MatrixXd jacobian(const VectorXd& p) const {
    MatrixXd out(coefficients(), parameters());
    for (Index i = 0; i < out.rows(); ++i) {
      for (Index k = 0; k < out.cols(); ++k) {
        out(i, k) = jacobian_[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)](p);
      }
    }
    return out;
  }

 private:
  Index parameters_ = 0;
  std::vector<Evaluator> value_;
  std::vector<std::vector<Evaluator>> jacobian_;
};

// The minimum-distance fit of one fit of the coefficients.
struct Distance {
  VectorXd p;
  MatrixXd covariance;  // NaN when the coefficients' covariance is unknown
  double q = kNaN;
  double cost = kNaN;  // (c - f(p))' W (c - f(p))
  bool converged = false;

  // What compares the minima of one search: Q, or the cost where Q is unknown (infinite where
  // the minimum does not determine the parameters).
  double score() const { return std::isfinite(q) ? q : cost; }
};

// The inverse of a symmetric matrix on its directions above 1e-12 of its largest eigenvalue,
// and the number of those kept from the largest down (all by default): empty when an element is
// not finite.
MatrixXd pseudo_inverse(const MatrixXd& m, Index keep = -1) {
  if (!m.allFinite()) return {};
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(m);
  const VectorXd& lambda = eigen.eigenvalues();  // ascending
  const Index n = m.rows(), from = keep < 0 ? 0 : std::max<Index>(0, n - keep);
  VectorXd inverse = VectorXd::Zero(n);
  for (Index i = from; i < n; ++i) {
    if (lambda(i) > 1e-12 * lambda.maxCoeff()) inverse(i) = 1 / lambda(i);
  }
  return eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
}

// The coefficients of one fit: their estimates, covariance V (its errors' long-run covariance,
// with what the fit adds to it) and the weight W of the distance. W is not V^-1: V comes from
// the errors' spectrum near frequency zero, a few tens of degrees of freedom, and the directions
// in which it happens to be small would take the weight, and the parameters along them errors
// several times too small (a two-mass chain sensed at mass 2, 40 records: k2 at z = +5.7 on one,
// its standard error a third of the others'). W is the inverse of the batch covariance of the
// same errors, known to as many degrees of freedom as there are batches (weights that are off by
// a common factor weigh the same); the parameters' covariance is V's projection through the
// fixed weights, which any weight makes right.
struct Coefficients {
  VectorXd value;
  MatrixXd covariance;  // V; empty when an error is unknown
  MatrixXd weight;      // W
};

Coefficients coefficients_of(const Fit& fit, const std::vector<std::vector<double>>& batches) {
  Coefficients out;
  const auto n = static_cast<Index>(fit.parameters.size());
  out.value.resize(n);
  for (Index i = 0; i < n; ++i) out.value(i) = fit.parameters[static_cast<std::size_t>(i)].estimate;
  out.covariance = matrix_of(fit.covariance(), n);
  if (!out.covariance.allFinite()) out.covariance.resize(0, 0);
  // Fewer batches than coefficients leave the batch covariance singular: V^-1 then.
  if (static_cast<Index>(batches.size()) > n + 1) {
    out.weight = pseudo_inverse(batch_covariance(matrix_of(batches, n)));
  }
  if (out.weight.size() == 0) out.weight = pseudo_inverse(out.covariance);
  if (out.weight.size() == 0) out.weight = MatrixXd::Identity(n, n);
  return out;
}

// The parameters that minimise (c - f(p))' W (c - f(p)) from `start` (Levenberg-Marquardt),
// their covariance L V L' for L = (F' W F)^-1 F' W, and Q = r' (M V M')^+ r for the residual
// r = c - f(p) and M = I - F L, whose covariance M V M' has rank `dof`: chi-square on `dof`
// degrees of freedom when the model's restrictions hold, whatever the weight.
Distance minimum_distance(const CoefficientMap& f, const Coefficients& c, int dof, VectorXd start) {
  Distance out;
  const MatrixXd& w = c.weight;
  const auto cost = [&](const VectorXd& p) {
    const VectorXd r = c.value - f.value(p);
    return r.allFinite() ? r.dot(w * r) : std::numeric_limits<double>::infinity();
  };
  VectorXd p = std::move(start);
  double now = cost(p), damping = 1e-3;
  constexpr int kIterations = 500;
  for (int iteration = 0; iteration < kIterations && std::isfinite(now); ++iteration) {
    const MatrixXd jac = f.jacobian(p);
    const MatrixXd normal = jac.transpose() * w * jac;
    const VectorXd gradient = jac.transpose() * w * (c.value - f.value(p));
    bool stepped = false;
    while (damping < 1e12) {
      MatrixXd damped = normal;
      damped.diagonal() += damping * normal.diagonal().cwiseMax(1e-12);
      const VectorXd step = damped.ldlt().solve(gradient);
      const double next = cost(p + step);
      if (next <= now) {
        const bool small = step.norm() <= 1e-12 * (1 + p.norm());
        p += step;
        stepped = true;
        out.converged = small || now - next <= 1e-14 * (1 + now);
        now = next;
        damping = std::max(damping / 4, 1e-12);
        break;
      }
      damping *= 8;
    }
    if (!stepped || out.converged) {
      out.converged = out.converged || stepped || now == 0;
      break;
    }
  }
  out.p = p;
  out.cost = now;
  out.covariance = MatrixXd::Constant(p.size(), p.size(), kNaN);
  if (c.covariance.size() == 0) return out;
  const MatrixXd jac = f.jacobian(p);
  const Eigen::FullPivLU<MatrixXd> lu(jac.transpose() * w * jac);
  if (!lu.isInvertible()) {
    // A minimum that does not determine the parameters (a chain's couplings all at 0) is no
    // answer: the search goes on from other starts.
    out.converged = false;
    out.q = std::numeric_limits<double>::infinity();
    return out;
  }
  const MatrixXd l = lu.inverse() * jac.transpose() * w;
  out.covariance = l * c.covariance * l.transpose();
  const VectorXd r = c.value - f.value(p);
  const MatrixXd m = MatrixXd::Identity(r.size(), r.size()) - jac * l;
  const MatrixXd q = pseudo_inverse(m * c.covariance * m.transpose(), dof);
  if (q.size() > 0 && dof > 0) out.q = r.dot(q * r);
  return out;
}

// The starts around nominal values that search_distance tries after them: each value times
// 10^u, u uniform in [-1, 1] (a nominal 0 taken as 1), its sign kept, from a fixed seed.
constexpr int kStarts = 64;
constexpr int kPolish = 8;
constexpr std::size_t kPolished = 8;

// The minimum distance from `nominal`, and where it does not converge or its Q is rejected,
// from kStarts more starts around it: the converged one of least Q. The coefficients are
// polynomials in the parameters, so Q has local minima in which a search from values far from
// the truth stops (a three-mass chain sensed at mass 1, with nominal values twice or half the
// truth: Q 112-1272 on 5 degrees of freedom on 7 of 12 records). Sets latent.starts and
// latent.nominal_distance.
Distance search_distance(const CoefficientMap& f, const Coefficients& coefficients,
                         const VectorXd& nominal, IdentifyResult::Latent& latent) {
  Distance best = minimum_distance(f, coefficients, latent.dof, nominal);
  const auto accepted = [&](const Distance& d) {
    return d.converged && (std::isnan(d.q) || latent.dof <= 0 ||
                           chi_square_upper_tail(d.q, latent.dof) >= Estimate::kJRejection);
  };
  if (accepted(best)) return best;
  latent.nominal_distance = best.q;
  // The searches of least Q, converged or not, are taken further (kPolished of them, kPolish
  // times at most): in the narrow valleys of strongly correlated parameters a search from afar
  // may stop at its iteration limit short of the minimum, and the least Q where the searches
  // stopped may lie in the valley of another one.
  std::vector<Distance> stopped;
  std::mt19937_64 random(20261130);
  std::uniform_real_distribution<double> exponent(-1, 1);
  for (latent.starts = 0; latent.starts < kStarts; ++latent.starts) {
    VectorXd start(nominal.size());
    for (Index k = 0; k < start.size(); ++k) {
      start(k) = (nominal(k) == 0 ? 1.0 : nominal(k)) * std::pow(10.0, exponent(random));
    }
    Distance d = minimum_distance(f, coefficients, latent.dof, start);
    if (std::isfinite(d.score())) stopped.push_back(std::move(d));
  }
  std::sort(stopped.begin(), stopped.end(),
            [](const Distance& a, const Distance& b) { return a.score() < b.score(); });
  stopped.resize(std::min<std::size_t>(stopped.size(), kPolished));
  for (Distance& d : stopped) {
    for (int round = 0; !d.converged && round < kPolish; ++round) {
      d = minimum_distance(f, coefficients, latent.dof, d.p);
    }
    if (d.converged && (!best.converged || d.score() < best.score())) best = d;
  }
  return best;
}

// The parameters' fit from the coefficients' fit.
Fit physical_fit(const Model& model, const Elimination& e, const Fit& coefficients,
                 const Distance& d) {
  Fit out;
  out.dof = coefficients.dof;
  out.objective = coefficients.objective;
  const double t = student_t_quantile(0.975, std::max(1.0, coefficients.dof));
  std::vector<Index> at(model.parameters().size(), -1);
  for (std::size_t k = 0; k < e.parameters.size(); ++k) {
    at[static_cast<std::size_t>(e.parameters[k])] = static_cast<Index>(k);
  }
  for (std::size_t p = 0; p < model.parameters().size(); ++p) {
    ParameterEstimate estimate{.name = model.parameters()[p].name};
    if (const auto known = e.fixed.find(static_cast<int>(p)); known != e.fixed.end()) {
      estimate.estimate = estimate.ci_low = estimate.ci_high = known->second.to_double();
      estimate.fixed = true;
    } else {
      const Index k = at[p];
      estimate.estimate = d.p(k);
      estimate.std_error = std::sqrt(d.covariance(k, k));
      estimate.ci_low = estimate.estimate - t * estimate.std_error;
      estimate.ci_high = estimate.estimate + t * estimate.std_error;
    }
    out.parameters.push_back(std::move(estimate));
  }
  if (!coefficients.correlation.empty()) {
    const std::size_t n = out.parameters.size();
    out.correlation.assign(n, std::vector<double>(n, kNaN));
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        if (at[i] < 0 || at[j] < 0) continue;
        out.correlation[i][j] = d.covariance(at[i], at[j]) /
                                (out.parameters[i].std_error * out.parameters[j].std_error);
      }
    }
  }
  return out;
}

// ModelError at the first parameter the coefficients leave undetermined.
void refuse_undetermined(const Model& model, const Elimination& e) {
  if (e.undetermined.empty()) return;
  const Elimination::Undetermined& u = e.undetermined.front();
  std::string names;
  for (std::size_t i = 0; i < u.parameters.size(); ++i) {
    names += (i == 0                         ? ""
              : i + 1 == u.parameters.size() ? " and "
                                             : ", ") +
             model.parameters()[static_cast<std::size_t>(u.parameters[i])].name;
  }
  const Declaration& first = model.parameters()[static_cast<std::size_t>(u.parameters.front())];
  std::string latent;
  for (int j : e.latent) {
    latent += (latent.empty() ? "" : ", ") + model.states()[static_cast<std::size_t>(j)].name;
  }
  throw ModelError(
      first.where,
      (u.parameters.size() == 1 ? "parameter " + names + " is" : "parameters " + names + " are") +
          " not determined by the record's channels once the latent states " + latent +
          " are eliminated: " +
          (u.parameters.size() == 1
               ? "no coefficient of the equations without them holds it (fix it"
               : "the coefficients of the equations without them hold them only in "
                 "combinations (fix " +
                     std::to_string(u.to_fix) + " of them") +
          ", e.g. " + UsageError::mention("fix") + " " + first.name + "=1, or `param " +
          first.name + " = 1 fixed`; docs/latent-states.md)");
}

}  // namespace

void identify_latent(IdentifyResult& result, const DataSource& source,
                     const IdentifyOptions& options, const std::vector<bool>& measured) {
  const AlgebraLock lock;
  const std::shared_ptr<const Model> model = result.model;
  const Elimination elimination = eliminate_latent(*model, measured, options.fixed);
  refuse_undetermined(*model, elimination);
  IdentifyResult::Latent latent;
  for (int j : elimination.latent)
    latent.states.push_back(model->states()[static_cast<std::size_t>(j)].name);
  latent.equations = format_text(*model, elimination);
  latent.coefficient_model = std::make_shared<const Model>(coefficient_model(*model, elimination));
  // The coefficients' model has parameters of its own: none of the model's is fixed there.
  IdentifyOptions coefficients_options = options;
  coefficients_options.fixed.clear();
  result.model = latent.coefficient_model;
  identify_lagged(result, source, coefficients_options, measured);
  result.model = model;

  Estimate& estimate = result.estimate;
  latent.coefficients = estimate.main().parameters;
  latent.dof = static_cast<int>(elimination.coefficients.size()) - elimination.rank;
  const CoefficientMap f(*model, elimination);
  VectorXd start(f.parameters());
  for (Index k = 0; k < start.size(); ++k) {
    const Declaration& d = model->parameters()[static_cast<std::size_t>(
        elimination.parameters[static_cast<std::size_t>(k)])];
    start(k) = d.value ? d.value->to_double() : 1.0;
  }
  if (!estimate.usable()) {
    // Nothing to map: the parameters' errors stay unknown, the status says why.
    for (Fit* fit : {&estimate.least_squares, estimate.optimal ? &*estimate.optimal : nullptr}) {
      if (fit == nullptr) continue;
      Distance none{.p = VectorXd::Constant(start.size(), kNaN),
                    .covariance = MatrixXd::Constant(start.size(), start.size(), kNaN)};
      *fit = physical_fit(*model, elimination, *fit, none);
      for (ParameterEstimate& p : fit->parameters) p.identifiable = p.fixed;
    }
    result.latent = std::move(latent);
    return;
  }
  const Distance main =
      search_distance(f, coefficients_of(estimate.main(), estimate.error_batches), start, latent);
  latent.distance = main.q;
  latent.converged = main.converged;
  if (std::isfinite(main.q) && latent.dof > 0) {
    latent.pvalue = chi_square_upper_tail(main.q, latent.dof);
  }
  if (estimate.optimal) {
    const Distance least = minimum_distance(
        f, coefficients_of(estimate.least_squares, estimate.error_batches), latent.dof, main.p);
    estimate.least_squares = physical_fit(*model, elimination, estimate.least_squares, least);
    *estimate.optimal = physical_fit(*model, elimination, *estimate.optimal, main);
  } else {
    estimate.least_squares = physical_fit(*model, elimination, estimate.least_squares, main);
  }
  result.latent = std::move(latent);
}

}  // namespace momentid
