// Term selection (docs/cli/select.md): the library identified from one pass, then subsets of
// its candidates scored on the library's fixed weighting.

#include "momentid/select.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "app/identify/lagged.hpp"
#include "app/identify/plan.hpp"
#include "common/number.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/validate.hpp"
#include "solve/delta_method.hpp"
#include "solve/distributions.hpp"
#include "solve/fixed.hpp"
#include "solve/selection.hpp"

namespace momentid {
namespace {

// Runner-up subsets within this much of the best criterion are reported as nearly as good
// (a difference of 2 in a BIC-type criterion is the usual "barely worth a mention").
constexpr double kCloseCriterion = 2;
// Candidates whose estimates on the library correlate beyond this are reported as collinear.
constexpr double kCollinear = 0.995;
// The best subset's J test p-value below which it is reported as rejected; the library's, below
// which its J over its degrees of freedom scales every J of the selection.
constexpr double kRejected = 0.01;

// The scoring of subsets over the free parameters on one weighting.
struct Scorer {
  const FixedWeighting& weighting;
  std::vector<bool> always;             // per free parameter: not a candidate
  std::vector<std::size_t> candidates;  // free-parameter indices
  double penalty = 0;
  double dispersion = 1;  // SelectResult::dispersion

  // Candidate flags -> free-parameter flags.
  std::vector<bool> kept(const std::vector<bool>& chosen) const {
    std::vector<bool> out = always;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      if (chosen[c]) out[candidates[c]] = true;
    }
    return out;
  }
  SelectResult::Subset score(const std::vector<bool>& chosen) const {
    SelectResult::Subset s;
    s.kept = kept(chosen);
    s.j = weighting.j(s.kept);
    s.dof = weighting.dof(s.kept);
    s.criterion = s.j / dispersion +
                  penalty * static_cast<double>(std::count(chosen.begin(), chosen.end(), true));
    s.pvalue = s.dof > 0 ? weighting.pvalue(s.kept) : std::numeric_limits<double>::quiet_NaN();
    return s;
  }
};

// The library's J over its degrees of freedom when its J test rejects it (on the test's own law,
// whose effective degrees of freedom may be far fewer than J's: docs/uncertainty.md), else 1:
// the misfit that no candidate explains (a noise or an offset not modelled, a law outside the
// library), by which every J of the selection is divided, as quasi-likelihood criteria divide
// deviances.
double dispersion_of(const FixedWeighting& weighting, std::size_t parameters) {
  const std::vector<bool> all(parameters, true);
  const int dof = weighting.dof(all);
  if (dof <= 0 || weighting.pvalue(all) >= kRejected) return 1;
  return weighting.j(all) / dof;
}

// Every subset, or the path of backward elimination, best first; `scored` counts them.
std::vector<SelectResult::Subset> search(const Scorer& scorer, bool exhaustive,
                                         std::size_t& scored) {
  const std::size_t n = scorer.candidates.size();
  std::vector<SelectResult::Subset> out;
  if (exhaustive) {
    for (std::size_t mask = 0; mask < (std::size_t{1} << n); ++mask) {
      std::vector<bool> chosen(n);
      for (std::size_t c = 0; c < n; ++c) chosen[c] = ((mask >> c) & 1U) != 0;
      out.push_back(scorer.score(chosen));
    }
    scored = out.size();
  } else {
    std::vector<bool> chosen(n, true);
    out.push_back(scorer.score(chosen));
    scored = 1;
    for (std::size_t left = n; left > 0; --left) {
      std::optional<SelectResult::Subset> best;
      std::size_t drop = 0;
      for (std::size_t c = 0; c < n; ++c) {
        if (!chosen[c]) continue;
        chosen[c] = false;
        SelectResult::Subset s = scorer.score(chosen);
        ++scored;
        chosen[c] = true;
        if (!best || s.criterion < best->criterion) {
          best = std::move(s);
          drop = c;
        }
      }
      chosen[drop] = false;
      out.push_back(std::move(*best));
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.criterion < b.criterion; });
  return out;
}

// Free-parameter flags -> flags over every parameter (fixed ones kept).
std::vector<bool> over_parameters(const std::vector<bool>& free_kept,
                                  const std::vector<std::optional<double>>& fixed) {
  std::vector<bool> out;
  std::size_t f = 0;
  for (const auto& value : fixed) out.push_back(value ? true : free_kept[f++]);
  return out;
}

// "y^2*v": the monomials parameter p multiplies, as its terms have them.
std::string terms_of(const Model& model, std::size_t p) {
  std::string out;
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      if (t.parameter != static_cast<int>(p)) continue;
      std::string term = format_monomial(model, t.monomial);
      if (t.derivative >= 0) {
        term = (term == "1" ? "" : term + "*") +
               model.states()[static_cast<std::size_t>(t.derivative)].name + "'";
      }
      out += (out.empty() ? "" : ", ") + term;
    }
  }
  return out;
}

// Whether parameter p multiplies the constant alone (the library term 1).
bool constant(const Model& model, std::size_t p) {
  bool found = false;
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      if (t.parameter != static_cast<int>(p)) continue;
      if (t.derivative >= 0 || t.monomial.degree() > 0) return false;
      found = true;
    }
  }
  return found;
}

// The library's equations at `system`'s lags, their fixed parameters moved to the right.
MomentRows free_rows(const IdentifyResult& library, const LaggedSystem& system,
                     const std::vector<std::optional<double>>& fixed) {
  return without_fixed(lagged_rows_of(library, system), fixed);
}

// The best subsets of the ranking (SelectOptions::kValidated at most), each identified on the
// record selected from (the chosen one already is), simulated through the inputs of
// options.validation and compared with it.
void validate_best(SelectResult& out, const DataSource& source, const SelectOptions& options) {
  const Model& library = *out.library.model;
  ValidateOptions validation;
  validation.replay.record = options.identify.record;
  validation.center = options.identify.center;
  const std::size_t count = std::min(out.ranking.size(), SelectOptions::kValidated);
  for (std::size_t rank = 0; rank < count; ++rank) {
    IdentifyResult identified;
    if (rank == 1 && out.runner_up) {
      identified = *out.runner_up;
    } else if (rank > 0) {
      const Model subset =
          parse_model(subset_model_text(out, out.ranking[rank].kept, out.library), library.file());
      IdentifyOptions unchecked = options.identify;
      unchecked.law_check = false;  // compared by their simulations
      identified = identify(subset, source, unchecked);
    }
    const IdentifyResult& estimated = rank == 0 ? out.chosen : identified;
    const Model model =
        parse_model(subset_model_text(out, out.ranking[rank].kept, estimated), library.file());
    SelectResult::Validated entry{rank};
    // The estimates' errors widen the noise band, as `validate --estimates FILE` takes them
    // (the subset's model and the one written from it have the same parameters).
    validation.covariance.clear();
    if (estimated.estimate.usable()) validation.covariance = estimated.estimate.main().covariance();
    try {
      const ValidateResult result = validate(model, *options.validation, validation);
      entry.consistent = result.consistent;
      for (const OutputFit& fit : result.outputs) {
        entry.outputs.push_back({fit.name, fit.fit, fit.rms});
      }
    } catch (const LocatedError&) {
      throw;  // the second record's own fault (a missing column, a bad field)
    } catch (const Error& e) {
      entry.consistent = false;
      entry.failed = e.what();  // its simulation blew up
    }
    out.validated.push_back(std::move(entry));
  }
  out.validation_name = options.validation->name();
}

// Options that choose other equations than the lagged ones, and counts out of range.
void check_options(const SelectOptions& options) {
  if (options.identify.method == Method::kZeroLag || options.identify.multipliers ||
      options.identify.degree > 0 || options.identify.extrapolate) {
    throw UsageError("method",
                     "select scores the terms on the lagged equations: multipliers, a degree, "
                     "the sampling bias and the zero-lag equations are identify's");
  }
  if (options.ranked == 0) throw UsageError("ranked", "expected at least 1 subset, found 0");
  if (options.exhaustive > SelectOptions::kMaxExhaustive) {
    throw UsageError("exhaustive", "every subset is scored for at most " +
                                       std::to_string(SelectOptions::kMaxExhaustive) +
                                       " candidates, found " + std::to_string(options.exhaustive));
  }
}

// The candidate parameters that are not fixed, or ModelError when there are none.
std::vector<std::size_t> candidates_of(const Model& model,
                                       const std::vector<std::optional<double>>& fixed) {
  std::vector<std::size_t> out;
  for (std::size_t p = 0; p < model.parameters().size(); ++p) {
    if (model.parameters()[p].candidate && !fixed[p]) out.push_back(p);
  }
  if (out.empty()) {
    throw ModelError({model.file(), 1, 1, ""},
                     "model " + model.name() +
                         " has no candidate terms: mark parameters with 'candidate NAME, ...' or "
                         "add terms with 'library v': y^2, y^3' (docs/model-language.md)");
  }
  return out;
}

// The whole library identified on the lagged equations with the optimal weighting.
IdentifyResult identify_library(const Model& model, const DataSource& source,
                                const SelectOptions& options) {
  IdentifyOptions identify_options = options.identify;
  identify_options.law_check = false;  // the chosen model's is the one that counts
  identify_options.method = Method::kLagged;
  identify_options.weighting = Weighting::kGmm;
  IdentifyResult library = identify(model, source, identify_options);
  library.why = "term selection scores the terms on them";
  if (!library.estimate.usable()) {
    throw Error("the library of model " + model.name() + " cannot be estimated on " +
                source.name() + ": " + library.estimate.message);
  }
  return library;
}

// What scores subsets on any window of the library's pass: the free parameters that are not
// candidates, the candidates among the free parameters, and the library's estimates.
struct Scoring {
  const Model& model;
  const IdentifyResult& library;
  const std::vector<std::optional<double>>& fixed;
  std::vector<bool> always;
  std::vector<std::size_t> free_candidates;
  double penalty = 0;
  Eigen::MatrixXd deviations;  // the library's moments' batch series, for every window

  Scoring(const Model& m, const SelectResult& out, const std::vector<std::optional<double>>& f)
      : model(m),
        library(out.library),
        fixed(f),
        penalty(out.penalty),
        deviations(batch_deviations(library.data.estimates)) {
    for (std::size_t p = 0; p < fixed.size(); ++p) {
      if (fixed[p]) continue;
      const bool candidate =
          std::find(out.candidates.begin(), out.candidates.end(), p) != out.candidates.end();
      if (candidate) free_candidates.push_back(always.size());
      always.push_back(!candidate);
    }
  }
  // The fixed weighting of the equations of `system`.
  FixedWeighting weighting(const LaggedSystem& system) const {
    return FixedWeighting(free_rows(library, system, fixed), always.size(), library.data.estimates,
                          deviations, library.lagged->moment_variance, true,
                          "term selection of model " + model.name());
  }
  Scorer scorer(const FixedWeighting& w) const {
    return Scorer{w, always, free_candidates, penalty, dispersion_of(w, always.size())};
  }
};

// The difference-in-J test of each candidate at the best subset, then a warning for each pair
// of candidates that are nearly collinear on the library.
void test_candidates(SelectResult& out, const Scoring& scoring, const Scorer& scorer,
                     const SelectResult::Subset& best) {
  const std::vector<std::size_t>& free_candidates = scoring.free_candidates;
  std::vector<bool> chosen(free_candidates.size());
  for (std::size_t c = 0; c < chosen.size(); ++c) chosen[c] = best.kept[free_candidates[c]];
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    std::vector<bool> other = chosen;
    other[c] = !other[c];
    const double j_other = scorer.score(other).j;
    const double difference = chosen[c] ? j_other - best.j : best.j - j_other;
    const std::size_t p = out.candidates[c];
    out.tests.push_back({scoring.model.parameters()[p].name, terms_of(scoring.model, p), chosen[c],
                         difference, chi_square_upper_tail(difference / out.dispersion, 1)});
  }
  for (std::size_t a = 0; a < free_candidates.size(); ++a) {
    for (std::size_t b = a + 1; b < free_candidates.size(); ++b) {
      const double rho = scorer.weighting.correlation(free_candidates[a], free_candidates[b]);
      if (std::abs(rho) > kCollinear) {
        out.warnings.push_back("candidates " + out.tests[a].name + " (" + out.tests[a].terms +
                               ") and " + out.tests[b].name + " (" + out.tests[b].terms +
                               ") are nearly collinear on these data (their estimates correlate " +
                               number(rho, "%.4f") +
                               " on the library): the selection between them is uncertain");
      }
    }
  }
}

// The warnings of the ranking itself: a library the J test rejects, a close runner-up.
void ranking_warnings(SelectResult& out, const std::vector<SelectResult::Subset>& ranking) {
  if (out.dispersion > 1) {
    out.warnings.push_back(
        "the J test rejects the whole library (J " + number(out.dispersion, "%.3g") +
        " times its degrees of freedom): the record holds a misfit that no candidate explains "
        "(a noise or an offset not modelled, a law outside the library), "
        "and the selection divides every J by that factor");
    out.uncertain.push_back("the library rejected");
  }
  if (ranking.size() > 1 && ranking[1].criterion - ranking[0].criterion < kCloseCriterion) {
    out.warnings.push_back("the runner-up is within " + number(kCloseCriterion, "%g") +
                           " of the best subset's criterion: the data hardly prefer one of them");
    out.uncertain.push_back(
        "the runner-up " + number(ranking[1].criterion - ranking[0].criterion, "%.2g") + " behind");
  }
}

// The same selection on narrower windows of the same pass, half and three quarters of the lags,
// and a warning when the chosen terms change with the window.
void select_on_windows(SelectResult& out, const Scoring& scoring, const LaggedSystem& system) {
  out.windows.push_back({system.first_lag, system.last_lag, out.ranking.front().kept});
  for (const int quarters : {2, 3}) {
    const int last = system.first_lag + (system.last_lag - system.first_lag) * quarters / 4;
    if (last - system.first_lag + 1 < LagOptions::kMinSpan) continue;
    LagOptions narrower;
    narrower.first_lag = system.first_lag;
    narrower.last_lag = last;
    narrower.instruments = system.instruments;
    narrower.measured = system.measured;
    const LaggedSystem sub = derive_lagged(scoring.model, narrower);
    const FixedWeighting weighting = scoring.weighting(sub);
    std::size_t scored = 0;
    const std::vector<SelectResult::Subset> ranking =
        search(scoring.scorer(weighting), out.exhaustive, scored);
    out.windows.push_back(
        {sub.first_lag, sub.last_lag, over_parameters(ranking.front().kept, scoring.fixed)});
  }
  for (std::size_t w = 1; w < out.windows.size(); ++w) {
    if (out.windows[w].kept == out.windows[0].kept) continue;
    out.warnings.push_back(
        "the chosen terms change with the lag window (see 'windows'): the "
        "selection is not stable on this record");
    out.uncertain.push_back("the terms change with the lag window");
    break;
  }
}

// The chosen model identified on its own equations, as identify takes the file it is written to
// (its instruments are its own, not the library's highest powers), and the warnings its tests
// and terms give, the tests' first.
void identify_chosen(SelectResult& out, const Model& model, const DataSource& source,
                     const SelectOptions& options) {
  out.chosen =
      identify(parse_model(chosen_model_text(out), model.file()), source, options.identify);
  if (out.chosen.estimate.j_pvalue && *out.chosen.estimate.j_pvalue < kRejected) {
    out.warnings.insert(out.warnings.begin(),
                        "the J test rejects the chosen model (p = " +
                            number(*out.chosen.estimate.j_pvalue, "%.2g") +
                            "): the library may lack a term the data need (an offset on a "
                            "measured channel puts a constant into its equation: the library "
                            "term 1)");
  }
  if (const auto* check = out.chosen.zero_lag_check(); check && check->rejects()) {
    out.warnings.insert(
        out.warnings.begin(),
        "the zero-lag check rejects the chosen model (p = " + number(*check->pvalue, "%.2g") +
            "): the library may lack the right law of a term, one the lagged "
            "equations cannot tell from the terms it has (abs(v)*v for a drag "
            "that v^3 stands in for; docs/measured-data.md, \"The zero-lag "
            "check\")");
  }
  for (std::size_t p = 0; p < model.parameters().size(); ++p) {
    if (out.ranking.front().kept[p] && model.parameters()[p].candidate && constant(model, p)) {
      out.warnings.push_back(
          "the constant " + model.parameters()[p].name +
          " is kept: the record's equilibrium is off zero (a sensor offset or a static load), "
          "and the other terms are in the record's coordinates, where an offset o turns a "
          "cubic spring into y^3, y^2 and y terms, k3 (y - o)^3 "
          "(docs/cli/select.md, \"Offsets\")");
    }
  }
}

// The runner-up subset identified on the record, as the chosen one is, when the structure is
// uncertain.
void identify_runner_up(SelectResult& out, const DataSource& source, const SelectOptions& options) {
  if (out.uncertain.empty() || out.ranking.size() < 2) return;
  const Model& library = *out.library.model;
  out.runner_up = identify(
      parse_model(subset_model_text(out, out.ranking[1].kept, out.library), library.file()), source,
      options.identify);
}

}  // namespace

Status status(const SelectResult& r) {
  const Status chosen = status(r.chosen);
  return chosen == Status::kOk && !r.uncertain.empty() ? Status::kDoubtful : chosen;
}

SelectResult select_terms(const Model& model, const DataSource& source,
                          const SelectOptions& options) {
  // The validation record is opened now: a file that cannot be read ends the run before the pass.
  if (options.validation) options.validation->open({});
  const AlgebraLock lock;
  check_options(options);
  const std::vector<std::optional<double>> fixed = fixed_values(model, options.identify.fixed);
  SelectResult out;
  out.candidates = candidates_of(model, fixed);
  out.library = identify_library(model, source, options);
  out.penalty =
      std::log(static_cast<double>(std::max<std::size_t>(out.library.estimate.intervals, 2)));
  out.exhaustive = out.candidates.size() <= options.exhaustive;
  const Scoring scoring(model, out, fixed);
  const LaggedSystem& system = *out.library.lagged->system;
  const FixedWeighting weighting = scoring.weighting(system);
  const Scorer scorer = scoring.scorer(weighting);
  out.dispersion = scorer.dispersion;
  std::vector<SelectResult::Subset> ranking = search(scorer, out.exhaustive, out.scored);
  test_candidates(out, scoring, scorer, ranking.front());
  ranking_warnings(out, ranking);
  ranking.resize(std::min(ranking.size(), options.ranked));
  for (SelectResult::Subset& s : ranking) s.kept = over_parameters(s.kept, fixed);
  out.ranking = std::move(ranking);
  select_on_windows(out, scoring, system);
  identify_chosen(out, model, source, options);
  identify_runner_up(out, source, options);
  if (options.validation) validate_best(out, source, options);
  return out;
}

}  // namespace momentid
