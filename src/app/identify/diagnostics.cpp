// What makes an identification doubtful, and every warning about it (docs/cli/identify.md,
// "Warnings").

#include <algorithm>
#include <cmath>
#include <numbers>

#include "app/identify/linearise.hpp"
#include "app/identify/response_means.hpp"
#include "common/number.hpp"
#include "momentid/identify.hpp"
#include "momentid/lagged.hpp"
#include "momentid/refine.hpp"

namespace momentid {
namespace {

// Sensor noise above this fraction of a state's standard deviation is reported. Below it the
// estimate cannot tell noise from the roughness of a state whose derivative holds a held input.
constexpr double kNoiseWarning = 0.02;

// What makes a result doubtful, and what draws a warning (docs/cli/identify.md, "Warnings").
constexpr double kIdentityZ = 4;    // |z| of a stationarity identity's violation
constexpr double kOffsetZ = 3;      // |mean| / its standard error, of a channel
constexpr double kWeakOffsetZ = 2;  // the same, named when the J test rejects the model
constexpr double kWeakRelativeError = 0.1;
constexpr double kUndeterminedZ = 2;  // |estimate| / its standard error, of every free parameter
constexpr double kStrongCorrelation = 0.95;
// Degrees of freedom of the main estimate's standard errors below which they are too rough to
// stand behind an interval: on short records (150 Duffing records of 2*10^4 samples,
// coverage.py held) every estimate more than 3.5 standard errors off (up to 10.5) had fewer
// than 7, and none of the rest beyond 3.2.
constexpr double kRoughErrorDof = 10;

// Whether every term of every equation is odd, counting a derivative as an odd factor: then the
// model is unchanged when every state and input changes sign, and zero-mean inputs give
// zero-mean states.
bool symmetric(const Model& model) {
  for (const Equation& eq : model.equations()) {
    for (const Term& t : eq.terms) {
      const Parity p = parity(model, t.monomial);
      if (p == Parity::kNone) return false;
      if ((p == Parity::kOdd) == (t.derivative >= 0)) return false;
    }
  }
  return true;
}

// A state whose mean lies off the mean the model gives it.
struct Offset {
  const ChannelMean* mean;
  // Where `expected` comes from: zero-mean inputs, the response to the inputs' means, or the
  // simulated response to the recorded inputs (IdentifyResult::response_means).
  enum class Expected { kZero, kInputMeans, kResponse } from = Expected::kZero;
  double expected = 0;  // the mean the model gives the state
  // The response has a mean of its own under zero-mean inputs (a periodic force on a nonlinear
  // model), which --center would remove with the offset.
  bool own_mean = false;
  double std_error = 0;  // of mean - expected
  double spread = 0;     // the state's standard deviation (0 when unknown)
};

// The states of a symmetric model whose means lie more than `z` standard errors from the mean the
// model gives them. Zero-mean random inputs give such a model zero-mean states; when an input's
// mean is off zero (a DAQ offset on the force), a state's mean may be off zero by the response to
// it, which the linearisation gives to first order (mean_response): the state is named when its
// mean lies further from that response than its error and the response itself together allow
// (the response of a hardening spring is smaller than the linearisation's, of a softening one
// larger). Where the model's response to the recorded inputs was simulated (response_means), its
// mean over the same rows is the expected one: a periodic force gives a nonlinear model's states
// a mean of their own, and the simulation has the inputs' means in it.
std::vector<Offset> offsets(const IdentifyResult& r, double z) {
  std::vector<Offset> out;
  if (!symmetric(*r.model)) return out;
  const auto& inputs = r.model->inputs();
  const auto input_of = [&](const ChannelMean& m) {
    return std::find_if(inputs.begin(), inputs.end(),
                        [&](const auto& d) { return d.name == m.name; });
  };
  const auto off = [&](const ChannelMean& m) {
    return m.std_error > 0 && std::abs(m.mean) > z * m.std_error;
  };
  const bool inputs_off = std::any_of(r.means.begin(), r.means.end(), [&](const ChannelMean& m) {
    return input_of(m) != inputs.end() && off(m);
  });
  const auto simulated = [&](const ChannelMean& m) {
    return std::find_if(r.response_means.begin(), r.response_means.end(),
                        [&](const auto& s) { return s.name == m.name; });
  };
  MeanResponse response;
  if (inputs_off && r.response_means.empty()) {
    response = mean_response(r);
    if (response.mean.empty()) return out;
  }
  const auto& states = r.model->states();
  // A state formed by integrating its derivative's column went through the high-pass filter,
  // which removes its mean whatever the sensor's offset: its mean tells nothing.
  const auto formed = [&](const ChannelMean& m) {
    return r.integration && std::any_of(r.integration->formed.begin(), r.integration->formed.end(),
                                        [&](const auto& f) { return f.state == m.name; });
  };
  for (const ChannelMean& m : r.means) {
    if (input_of(m) != inputs.end() || !(m.std_error > 0) || formed(m)) continue;
    Offset o{&m};
    const auto state =
        std::find_if(states.begin(), states.end(), [&](const auto& d) { return d.name == m.name; });
    if (const auto sim = simulated(m); sim != r.response_means.end()) {
      o.from = Offset::Expected::kResponse;
      o.expected = sim->simulated + (m.mean - sim->recorded);
      // The pass's error of the mean, or the simulation's where it follows the record loosely.
      o.std_error = std::max(m.std_error, sim->std_error);
      o.own_mean = !inputs_off && std::abs(o.expected) > kWeakOffsetZ * o.std_error;
      if (!(std::abs(m.mean - o.expected) > z * o.std_error)) continue;
    } else if (inputs_off) {
      // A derivative column: its response is not known (nor simulated).
      if (state == states.end() || response.mean.empty()) continue;
      const auto s = static_cast<std::size_t>(state - states.begin());
      o.from = Offset::Expected::kInputMeans;
      o.expected = response.mean[s];
      double variance = m.std_error * m.std_error;
      for (const ChannelMean& u : r.means) {
        const auto input = input_of(u);
        if (input == inputs.end()) continue;
        const double g = response.gain[s][static_cast<std::size_t>(input - inputs.begin())];
        variance += g * g * u.std_error * u.std_error;
      }
      o.std_error = std::sqrt(variance);
      if (!(std::abs(m.mean - o.expected) > z * o.std_error + std::abs(o.expected))) continue;
    } else {
      if (!off(m)) continue;
      o.std_error = m.std_error;
    }
    o.spread = spread_of(r, m.name);
    out.push_back(o);
  }
  return out;
}

// "'y' has the mean 0.0123, 0.12 of its standard deviation (5.1 standard errors from zero)", or
// "... (5.1 standard errors from the 0.0004 that the inputs' means give it)", or "'y' has the
// mean 0.0123, 0.0119 from the 0.0004 of its response to the recorded inputs (0.12 of its
// standard deviation, 5.1 standard errors)".
std::string mean_text(const Offset& o) {
  const ChannelMean& m = *o.mean;
  std::string out = "'" + m.name + "' has the mean " + number(m.mean, "%.3g");
  if (o.from == Offset::Expected::kResponse) {
    out += ", " + number(m.mean - o.expected, "%.3g") + " from the " + number(o.expected, "%.3g") +
           " of its response to the recorded inputs (";
    if (o.spread > 0) {
      out +=
          number(std::abs(m.mean - o.expected) / o.spread, "%.2g") + " of its standard deviation, ";
    }
    return out + number(std::abs(m.mean - o.expected) / o.std_error, "%.2g") + " standard errors)";
  }
  if (o.spread > 0) {
    out += ", " + number(std::abs(m.mean) / o.spread, "%.2g") + " of its standard deviation";
  }
  out += " (" + number(std::abs(m.mean - o.expected) / o.std_error, "%.2g") +
         " standard errors from " +
         (o.from == Offset::Expected::kZero
              ? std::string("zero")
              : "the " + number(o.expected, "%.3g") + " that the inputs' means give it") +
         ")";
  return out;
}

// How to remove the offset `o`: --center, unless the state's response has a mean of its own.
std::string remedy(const Offset& o) {
  const std::string& name = o.mean->name;
  if (!o.own_mean) return "remove it with --center " + name;
  return "subtract about " + number(o.mean->mean - o.expected, "%.3g") + " from '" + name +
         "' (--center would remove the mean of the response too)";
}

// "the identified model is unstable: ..." (Runaway), with the damping ratio of the growing mode
// and its standard error when it oscillates.
std::string runaway_text(const Runaway& away) {
  std::string growth = "grows as exp(" + number(away.growth_rate, "%.3g") + " t)";
  if (away.frequency_hz > 0) {
    const double omega = 2 * std::numbers::pi * away.frequency_hz;
    growth += ", a mode at " +
              number(std::hypot(omega, away.growth_rate) / (2 * std::numbers::pi), "%.3g") + " Hz";
    if (away.damping_ratio < 0) {
      growth += " with the damping ratio " + number(away.damping_ratio, "%.2g");
      if (std::isfinite(away.damping_se)) {
        growth += " (standard error " + number(away.damping_se, "%.2g") + ")";
      }
    }
  }
  return "the identified model is unstable: linearised at its equilibrium it " + growth +
         ", and its free response " +
         (std::isnan(away.time) ? std::string("keeps growing for as long as it was followed")
                                : "leaves a thousand standard deviations of the states at t = " +
                                      number(away.time, "%.3g")) +
         ", which no stationary record comes from. A term or an instrument may be missing, or "
         "the data not determine the damping: do not simulate with these estimates";
}

// Whether no free parameter lies further than kUndeterminedZ standard errors from zero.
bool undetermined(const IdentifyResult& r) {
  bool any = false;
  for (const ParameterEstimate& p : r.parameters()) {
    if (p.fixed || !p.identifiable) continue;
    if (!(std::abs(p.estimate) <= kUndeterminedZ * p.std_error)) return false;
    any = true;
  }
  return any;
}

// The doubts of a state's derivative whose only coefficient is a free parameter within
// kUndeterminedZ standard errors of zero (m3 of a' in m3*a' = -a - c*v + ...): the data do not
// tell the model from one without that derivative, and the fast mode it adds is stable or
// unstable as the estimate's sign falls (a third-order model of a second-order oscillator, on
// records that differ in their noise alone: tests/independent/unstable.py jerk).
std::vector<std::string> undetermined_orders(const IdentifyResult& r) {
  std::vector<std::string> out;
  const Model& model = *r.model;
  for (std::size_t s = 0; s < model.states().size(); ++s) {
    const Term* only = nullptr;
    std::size_t count = 0;
    for (const Equation& eq : model.equations()) {
      for (const Term& t : eq.terms) {
        if (t.derivative != static_cast<int>(s)) continue;
        only = &t;
        ++count;
      }
    }
    if (count != 1 || only->parameter < 0) continue;
    const std::string& name = model.parameters()[static_cast<std::size_t>(only->parameter)].name;
    const std::vector<ParameterEstimate>& parameters = r.parameters();
    const auto p = std::find_if(parameters.begin(), parameters.end(),
                                [&](const ParameterEstimate& q) { return q.name == name; });
    if (p == parameters.end() || p->fixed || !p->identifiable || !(p->std_error > 0) ||
        !(std::abs(p->estimate) <= kUndeterminedZ * p->std_error)) {
      continue;
    }
    const std::string derivative = model.states()[s].name + "'";
    out.push_back("the coefficient " + name + " of " + derivative + " is " +
                  number(std::abs(p->estimate) / p->std_error, "%.2g") +
                  " standard errors from zero: the data do not tell this model from one without " +
                  derivative +
                  ", a derivative order they do not determine, and the mode it adds "
                  "is stable or unstable as the estimate's sign falls. Write the model without " +
                  derivative);
  }
  return out;
}

}  // namespace

std::vector<std::string> doubts(const IdentifyResult& r) {
  std::vector<std::string> out;
  if (std::optional<std::string> outlier = outlier_warning(r.data)) out.push_back(*outlier);
  const Estimate& e = r.estimate;
  // The J test comes with the optimal weighting.
  if (e.j_pvalue && *e.j_pvalue < Estimate::kJRejection) {
    // Offsets too small for a warning of their own may still be what the test sees.
    std::string seen;
    const std::vector<Offset> strong = offsets(r, kOffsetZ);
    for (const Offset& o : offsets(r, kWeakOffsetZ)) {
      seen += "; " + mean_text(o) + ": an offset? " + remedy(o);
      if (std::any_of(strong.begin(), strong.end(),
                      [&](const Offset& s) { return s.mean == o.mean; })) {
        seen += " (see below)";
      }
    }
    // A state formed from an acceleration in a nonlinear term is a misfit of the model's own,
    // where it could not be taken out.
    std::string cut;
    if (r.integration && !(r.integration->misfit && r.integration->misfit->failure.empty())) {
      for (const IdentifyResult::Integration::Formed& f : r.integration->formed) {
        if (f.cut) cut += (cut.empty() ? "'" : ", '") + f.state + "'";
      }
    }
    if (!cut.empty()) {
      cut = "; or the low frequencies the filter cuts from " + cut +
            ", formed from accelerations, in the nonlinear terms (see the warning): a misfit "
            "of the right model too, which a precise record shows and a displacement sensor's "
            "column for that state removes";
    }
    out.push_back("the J test rejects the model (p = " + number(*e.j_pvalue, "%.2g") +
                  "): its moment equations disagree with each other more than their errors "
                  "allow. A term may be missing, a noise or an offset not modelled, or the "
                  "record too coarsely sampled: check the estimates with 'momentid validate' "
                  "before using them" +
                  seen + cut);
  }
  if (const auto* check = r.zero_lag_check(); check && check->rejects()) {
    out.push_back("the zero-lag check rejects the model (p = " + number(*check->pvalue, "%.2g") +
                  "): the zero-lag equations up to degree " + std::to_string(check->degree) +
                  ", which weigh the tails of the states' distribution, give estimates that "
                  "differ from the lagged ones by more than their errors allow. A term may be "
                  "missing or have the wrong form (a law of damping or stiffness), or an offset "
                  "not modelled: compare candidate models with 'momentid select'");
  }
  for (const IdentityCheck& c : e.identities) {
    if (!(std::abs(c.z) > kIdentityZ)) continue;
    out.push_back("the stationarity identity " + c.identity +
                  " is violated (z = " + number(c.z, "%.3g") +
                  "): the record is not stationary (a drift, a start-up transient, runs joined "
                  "end to end), or its columns are not what the model's kinematic equations say "
                  "(v is not y', or the channels are shifted in time)");
  }
  for (const IdentifyResult::LawCheck& c : r.law_checks) {
    if (!(std::abs(c.z) > IdentifyResult::kLawZ)) continue;
    out.push_back("the law check rejects the damping law: " + c.term +
                  " added to the equation of " + c.equation + " is " + number(c.z, "%.3g") +
                  " standard errors from zero, where a right law leaves it within " +
                  number(IdentifyResult::kLawZ, "%g") +
                  ": the data call for that law, which the model's term stands in for (Coulomb "
                  "friction and quadratic drag are nearly collinear over a record, and the J test "
                  "sees the wrong one weakly; docs/measured-data.md, \"The law check\"). Compare "
                  "the two with 'momentid select'");
  }
  if (const auto& i = r.integration; i && i->misfit && !i->misfit->channel.empty()) {
    out.push_back(
        "the identified model's response to the recorded inputs does not follow the "
        "record: its '" +
        i->misfit->channel + "' spreads " + number(i->misfit->spread, "%.3g") +
        " times as far as the record's (less its noise). A term may be missing or "
        "have the wrong form, or a column not be what the model says it is; 'momentid "
        "validate' shows the response against the record");
  }
  const std::vector<std::string> orders = undetermined_orders(r);
  out.insert(out.end(), orders.begin(), orders.end());
  if (r.runaway) out.push_back(runaway_text(*r.runaway));
  if (const auto& l = r.latent; l && e.usable()) {
    // Where the search from the nominal values failed, it ran from l->starts more values.
    const std::string around =
        l->starts > 0 ? " and " + std::to_string(l->starts) + " values around them" : "";
    if (!l->converged) {
      out.push_back(
          "the search for the parameters from the coefficients of the equations without the "
          "latent states did not converge from the model's nominal values" +
          around + ": give values nearer the truth in the model (docs/latent-states.md)");
    } else if (l->pvalue && *l->pvalue < Estimate::kJRejection) {
      out.push_back(
          "the coefficients of the equations without the latent states contradict "
          "the model's relations between them (Q = " +
          number(*l->distance, "%.4g") + " on " + std::to_string(l->dof) +
          " degrees of freedom, p = " + number(*l->pvalue, "%.2g") +
          (l->starts > 0 ? ", the least from the model's nominal values" + around : "") +
          "): the latent dynamics may be wrong, or the nominal values too far from the truth "
          "for the search (docs/latent-states.md)");
    }
  }
  if (r.refinement) {
    for (const std::string& w : r.refinement->warnings) {
      out.push_back("the simulation-error refinement: " + w);
    }
  }
  if (!r.refinement_failure.empty()) {
    out.push_back("the simulation-error refinement could not run: " + r.refinement_failure);
  }
  const Fit& main = e.main();
  const bool has_errors =
      std::any_of(main.parameters.begin(), main.parameters.end(), [](const ParameterEstimate& p) {
        return !p.fixed && p.identifiable && std::isfinite(p.std_error);
      });
  if (has_errors && main.dof < kRoughErrorDof) {
    out.push_back("the standard errors rest on " + number(main.dof, "%.3g") +
                  " degrees of freedom (their long-run covariance, from " +
                  std::to_string(e.batches) +
                  " batches): they are rough, and on records this short some were several times "
                  "too small (docs/cli/identify.md, \"Warnings\"). Use a longer record");
  }
  if (undetermined(r)) {
    out.push_back("no parameter is determined: every estimate lies within " +
                  number(kUndeterminedZ, "%g") +
                  " standard errors of zero, so the data do not tell this model from one without "
                  "any of its terms. Excite the system more, measure longer, or remove terms");
  }
  for (const Offset& o : offsets(r, kOffsetZ)) {
    out.push_back(
        mean_text(o) + ", but model " + r.model->name() + " is symmetric (every term odd), " +
        (o.from == Offset::Expected::kZero ? "and its inputs have no mean, so its states have none"
         : o.from == Offset::Expected::kInputMeans
             ? "so its states have no mean but the response to the inputs' means"
             : "so its states have no mean but that of its response to the recorded "
               "inputs (the identified model simulated through them)") +
        ": a sensor offset? It biases the estimates; if it is one, " + remedy(o) +
        (r.response_failure.empty()
             ? ""
             : ". A periodic input can give a state a mean of its own, which the "
               "identified model's response to the recorded inputs would show, but " +
                   r.response_failure));
  }
  return out;
}

bool offset_in_doubt(const IdentifyResult& r) {
  return symmetric(*r.model) &&
         (!offsets(r, kWeakOffsetZ).empty() ||
          (r.estimate.j_pvalue && *r.estimate.j_pvalue < Estimate::kJRejection));
}

Status status(const IdentifyResult& r) {
  if (r.estimate.status != Status::kOk) return r.estimate.status;
  if (!doubts(r).empty()) return Status::kDoubtful;
  return r.estimate.j_pvalue ? Status::kOk : Status::kUntested;
}

namespace {

// Why no J test checked the model of an untested result.
std::string untested_text(const IdentifyResult& r) {
  std::string why;
  if (r.estimate.optimal) {
    why = "the optimal weighting left no degrees of freedom for the J test";
  } else if (r.gmm) {
    why = "the optimal weighting could not be made (see its warning)";
  } else if (const auto& p = r.estimate.main().parameters;
             r.estimate.rows <= static_cast<std::size_t>(std::count_if(
                                    p.begin(), p.end(), [](const auto& q) { return !q.fixed; }))) {
    why = "there are no more equations than parameters";
  } else {
    why = "least squares was asked for, and only the optimal weighting has the J test";
  }
  return "no test checked the model: " + why +
         ". The estimates fit these equations exactly or nearly so whether the model is right or "
         "not; more equations (multipliers of a higher degree, more instruments) and the optimal "
         "weighting give the J test";
}

}  // namespace

std::vector<std::string> warnings(const IdentifyResult& r) {
  std::vector<std::string> w;
  if (r.estimate.status != Status::kOk) w.push_back(r.estimate.message);
  const std::vector<std::string> doubt = doubts(r);
  w.insert(w.end(), doubt.begin(), doubt.end());
  if (status(r) == Status::kUntested) w.push_back(untested_text(r));
  // The optimal weighting that was asked for and could not be made: before the rest.
  for (const std::string& s : r.estimate.warnings) {
    if (s.rfind("no optimally weighted estimate", 0) == 0) w.push_back(s);
  }
  const std::vector<ParameterEstimate>& parameters = r.parameters();
  for (const ParameterEstimate& p : parameters) {
    if (!p.identifiable || !(std::abs(p.std_error) > kWeakRelativeError * std::abs(p.estimate))) {
      continue;
    }
    w.push_back("'" + p.name + "' is weakly determined: its standard error is " +
                number(100 * p.std_error / std::abs(p.estimate), "%.3g") +
                "% of its value. Excite the system more, add multipliers (--degree) or fix "
                "parameters you know");
  }
  const auto& correlation = r.estimate.main().correlation;
  for (std::size_t i = 0; i < correlation.size(); ++i) {
    for (std::size_t j = i + 1; j < correlation.size(); ++j) {
      if (!(std::abs(correlation[i][j]) > kStrongCorrelation)) continue;
      w.push_back("the estimates of '" + parameters[i].name + "' and '" + parameters[j].name +
                  "' are strongly correlated (" + number(correlation[i][j], "%.3f") +
                  "): the data determine a combination of them better than each");
    }
  }
  std::vector<std::string> rest = data_warnings(r.data);
  for (const ChannelStatistics& c : r.data.channels) {
    const std::optional<double> fraction = c.noise_fraction();
    if (c.is_input || !fraction || *fraction < kNoiseWarning) continue;
    // The warning on the noise's range says what the estimate holds.
    if (r.lagged && r.lagged->rough_noise && r.lagged->rough_noise->channel == c.name) continue;
    rest.push_back("'" + c.name + "' carries white noise of about " +
                   number(100 * *fraction, "%.2g") +
                   "% of its standard deviation (the excess of its autocorrelation at lag 0): " +
                   (r.lagged ? "the lagged equations correct its powers, but the estimates are "
                               "less certain and may still be biased"
                             : "it biases the zero-lag estimates (the lagged equations, --lags, "
                               "correct for it in part)"));
  }
  if (r.zero_lag && r.zero_lag->held_input && !r.model->functions().empty() &&
      !r.zero_lag->held_input->unavailable.empty()) {
    rest.push_back(
        "the input is held over each sample and the model has abs(...) or sign(...) "
        "terms, for which the kinks it puts into the states are not corrected: the "
        "estimates carry a bias of order dt^2 that their errors do not include (on a "
        "drag oscillator under simulate's default input at dt = 0.01, 3.7 standard "
        "errors in k over 10^6 samples); a finer dt, or a band-limited force sampled "
        "rather than held, makes it smaller");
  }
  if (r.lagged && r.lagged->rough_noise) {
    const IdentifyResult::Lagged::RoughNoise& n = *r.lagged->rough_noise;
    rest.push_back("the noise on '" + n.channel +
                   "' cannot be told from the signal at this sampling: its sixth differences "
                   "give a noise variance of " +
                   number(n.sixth, "%.3g") + ", its fourth differences " +
                   number(n.fourth, "%.3g") +
                   " (a record not smooth at the sample scale: a resonance sampled coarsely, or "
                   "harmonics near the Nyquist frequency), so up to " +
                   number(100 * n.share, "%.0f") +
                   "% of the estimate may be signal. The estimates take the middle of that range "
                   "and their errors its spread (" +
                   n.parameter + " moves by " + number(n.shift, "%.2g") +
                   " standard errors across it); the sensor's noise, if known (--noise " +
                   n.channel + "=VARIANCE), or a faster sampling removes it");
  }
  if (r.lagged) {
    for (const auto& [name, tau] : r.lagged->correlation_lags) {
      if (tau != 0) continue;
      rest.push_back("'" + name + "' stays correlated across lags " +
                     std::to_string(r.lagged->system->first_lag) + ".." +
                     std::to_string(r.lagged->system->last_lag) +
                     " (its autocorrelation stays above 1/e): the lagged equations see less than a "
                     "correlation time of it; give --lags a longer window (with fewer instruments "
                     "if the moments run out) or keep every n-th sample of the record");
    }
  }
  for (const std::string& s : r.estimate.warnings) {
    if (s.rfind("no optimally weighted estimate", 0) != 0) rest.push_back(s);
  }
  w.insert(w.end(), rest.begin(), rest.end());
  return w;
}

}  // namespace momentid
