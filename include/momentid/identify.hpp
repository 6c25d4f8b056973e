#pragma once

#include <cmath>
#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "momentid/accumulator.hpp"
#include "momentid/data_pass.hpp"
#include "momentid/fit.hpp"
#include "momentid/moment.hpp"
#include "momentid/reader.hpp"
#include "momentid/record_options.hpp"
#include "momentid/types.hpp"

// This header, and those it includes, do not include GiNaC (the test library.ginac_free
// checks it): a program that identifies a record needs no computer algebra. The model and the
// moment equations stay incomplete types here; model.hpp, derive.hpp and lagged.hpp define them.
namespace momentid {

struct RefineResult;  // momentid/refine.hpp

class Model;
struct MomentSystem;
struct LaggedSystem;

// How to identify (docs/cli/identify.md, "momentid identify"). The defaults are the command line's.
struct IdentifyOptions {
  // The record's columns, sample interval, layout and input hold, and each pass's threads,
  // shards and progress (every field is used).
  RecordOptions record;
  // Multipliers for every equation; else all monomials up to `degree` (when > 0); else the
  // model's own or the automatic choice (see DeriveOptions).
  std::optional<std::vector<Monomial>> multipliers;
  int degree = 0;
  // Contiguous batches for the standard errors, kMinBatches..kMaxBatches; nullopt: automatic
  // (DataOptions::batches), and at least four per equation for the optimal weighting.
  std::optional<std::size_t> batches;
  // Which moment equations: kAuto takes the lagged ones unless the record is known to be
  // noise-free (simulate's output without noise), or options for the zero-lag ones (multipliers,
  // a degree, extrapolate) are given, or the data give no sample interval; IdentifyResult::why
  // says which was taken and why.
  Method method = Method::kAuto;
  // The main estimate: kAuto takes the optimally weighted one (GMM), with the J test
  // that gives `ok` its meaning, whenever the equations outnumber the free parameters; least
  // squares is always computed beside it.
  Weighting weighting = Weighting::kAuto;
  // Pair input row n with state row n + input_shift, within kMaxInputShift either way.
  long input_shift = 0;
  // Lagged moment equations (docs/measured-data.md) at lags first..last samples, with these
  // instruments (nullopt: a window the data's correlation times call for, and derive_lagged's
  // instruments, both cut to kMaxLaggedMoments). Giving either chooses the lagged equations.
  std::optional<std::pair<int, int>> lags;
  std::optional<std::vector<Monomial>> instruments;
  // White sensor noise on the states, for the lagged equations, which replace powers of noisy
  // channels by their Hermite polynomials: nullopt estimates each measured state's noise
  // variance from its autocorrelation; a map gives the variances by name (absent: none).
  std::optional<std::map<std::string, double>> noise;
  // Parameters taken as known, by name, besides those declared `fixed` in the model file (a
  // value here wins): their terms move to the right-hand side.
  std::map<std::string, double> fixed;
  // Model variables whose mean is removed before the moments are formed (a sensor offset on a
  // symmetric system): the means come from a first pass over the data.
  std::vector<std::string> center;
  // States to form from the column of their derivative (`--integrate y`), for records that show
  // them only through it (y'' = a) and models with terms nonlinear in them: the column is
  // integrated in the pass inside a high-pass filter that every channel goes through
  // (DataOptions::Integration), with the corner `integrate_corner` (Hz), by default half the
  // lowest frequency of the record's band (docs/model-language.md). The formed state is then
  // read as measured, biased where the filter cuts its nonlinear terms' low frequencies. Empty
  // (and no `instruments`): the states the lagged equations cannot do without are formed
  // (IdentifyResult::Integration::by_default), with `integrate_corner` too; where none is, a
  // corner given is warned of as having no effect.
  std::vector<std::string> integrate;
  std::optional<double> integrate_corner;
  // The sampling bias (`--extrapolate dt`): the zero-lag estimate again from every other sample
  // of a record whose inputs are samples of a continuous signal (not held), both halves; their
  // difference estimates the bias of the estimate at the data's dt, which is removed
  // (Richardson's extrapolation to dt = 0) when it exceeds its standard error.
  bool extrapolate = false;
  // The simulation-error refinement (`--refine`, docs/refine.md): the model simulated through
  // the record's inputs, its error in the measured channels minimised from the estimate
  // (IdentifyResult::refinement). A refined value outside the estimate's 95% interval is a doubt.
  bool refine = false;
  // The law check of a drag or friction term (IdentifyResult::law_checks): a second
  // identification with the other law added. `select` leaves it to the chosen model.
  bool law_check = true;

  static constexpr std::size_t kMinBatches = 2, kMaxBatches = 10000;
  static constexpr int kMaxDegree = 12;
  static constexpr long kMaxInputShift = 1000;
  // The lagged equations may need at most this many moments: the accumulator keeps each of them
  // per stretch of the record, and the stretches grow with the batches that the weighting needs
  // per equation, so that memory and time grow with moments times equations (docs/benchmarks.md:
  // the ten-mass chain's full window with every instrument takes 40 times the default's time
  // for 6% smaller errors).
  static constexpr std::size_t kMaxLaggedMoments = 3000;

  // Throws UsageError naming the first option that is out of range or that names a variable
  // `model` does not have.
  void validate(const Model& model) const;
};

// A channel's mean over the record, with its standard error (from the batches' long-run
// covariance): a mean many errors from zero in a state of a symmetric model is a sensor offset.
struct ChannelMean {
  std::string name;
  double mean = 0;
  double std_error = 0;
};

// An identified model that runs away from its equilibrium, which no stationary record comes
// from: its linearisation there (under the inputs' means, Newton from the origin) has an
// eigenvalue of positive real part, and its free response, started a thousandth of the measured
// states' standard deviations off along that eigenvalue's direction and followed for 4 ln(10^6)
// e-folding times, leaves a thousand of them or still grows at the end (its largest size in the
// last quarter of that time is more than twice that in the third). A model that its nonlinear
// terms hold (a Van der Pol limit cycle, a double well) settles. Empty when the model is stable
// at its equilibrium or held, has no equilibrium or no linearisation there (an abs or sign term
// switching), or no state has a channel to scale it by. `time` is NaN when the response did not
// leave the bound (it kept growing, or 200,000 steps did not reach the end: the growth is too
// slow).
struct Runaway {
  double growth_rate = 0;   // the largest real part of the eigenvalues, per unit of time
  double frequency_hz = 0;  // of that eigenvalue (0 for a real one)
  // Of an oscillating mode, its (negative) damping ratio and standard error (linearised_modes);
  // NaN for a real eigenvalue.
  double damping_ratio = NAN, damping_se = NAN;
  double time = NAN;  // when the free response left the bound
};
// What an identification yields: the moment equations (zero-lag or lagged, whichever the data
// called for), the moments estimated from the data, and the estimate with its diagnostics. The
// result owns everything it holds, a copy of the model included, so it stays valid after the
// model and the source are gone.
struct IdentifyResult {
  // The zero-lag moment equations and what refined their estimate.
  struct ZeroLag {
    std::shared_ptr<const MomentSystem> system;  // derive.hpp; refers to *model
    std::vector<Monomial> moments;               // the moments of data.estimates, in that order
    // IdentifyOptions::extrapolate: per parameter of the main result, the estimate from every
    // other sample, the bias of the estimate at dt, (fine - coarse) / (2^order - 1), and the
    // standard error of fine - coarse. `applied`: the difference exceeds its standard error for
    // some parameter, and the main result is the extrapolated estimate (its errors those of the
    // extrapolation).
    struct SamplingBias {
      static constexpr int kOrder = 2;  // of the bias in dt (docs/uncertainty.md, "Sampling bias")
      std::vector<double> coarse, bias, difference_error;
      bool applied = false;
    };
    std::optional<SamplingBias> sampling_bias;
    // Data whose input is held over each sample: the moments whose derivative holds the input
    // were corrected for the kinks it puts into the states at the samples (derive.hpp,
    // held_input_corrections). `shift`: per parameter of the main result, the corrected estimate
    // minus the uncorrected one; empty, with `unavailable` saying why, when no correction could
    // be made.
    struct HeldInput {
      std::vector<double> shift;
      std::string unavailable;
    };
    std::optional<HeldInput> held_input;
    // The zero-lag equations take the stationarity identities E[(g)'] = 0, which a finite record
    // meets only up to (g(end) - g(start)) / T. The errors that leave are estimated from the
    // variances of the monomials g (SolveOptions::rate_covariance), and the batch series of the
    // rates, from the first and last rows of each batch, take them out of the batches' errors.
    // Set when the equations use such identities; `unavailable` says why the batches had to
    // estimate them instead (no sample interval, or more products g_i*g_j than the pass reads
    // otherwise).
    struct EndValues {
      std::string unavailable;
    };
    std::optional<EndValues> end_values;
  };
  // The lagged moment equations and their moments, over `channels` (data columns, by model name).
  struct Lagged {
    std::shared_ptr<const LaggedSystem> system;  // lagged.hpp; refers to *model
    std::vector<Moment> moments;                 // the moments of data.estimates, in that order
    std::vector<std::string> channels;
    std::vector<double> noise;  // the noise variance used per channel
    // The noise that formed states share with their columns (estimate.hpp), with the variances.
    SharedNoise shared_noise;
    int stencil_reach = 0;  // of the lag-derivative stencils
    // Per moment: the variance of the accuracy floor added to its errors (SolveOptions).
    std::vector<double> moment_variance;
    // Per measured state the equations read: the lag at which its autocorrelation first falls
    // below 1/e, 0 if it stays above across the lags, -1 if the pass did not read it.
    std::map<std::string, int> correlation_lags;
    // A state channel whose noise could not be told from the signal's roughness at the sample
    // scale (a coarsely sampled resonance, its harmonics): the noise estimate from its sixth
    // differences, the same from its fourth (more than kRoughNoise times it), the share of the
    // estimate that may be signal (their difference over the 0.46 by which the fourth's weight
    // exceeds the sixth's at a third of the sample rate, at most 1), and the parameter whose
    // estimate moves most, in standard errors, over that range of the noise. The estimate is
    // solved at the middle of the range, its errors take the spread over it (lagged.cpp).
    struct RoughNoise {
      std::string channel;
      double sixth = 0, fourth = 0, share = 0;
      std::string parameter;
      double shift = 0;
    };
    static constexpr double kRoughNoise = 1.25;
    std::optional<RoughNoise> rough_noise;
    // What was cut from the default lags and instruments to stay within kMaxLaggedMoments, e.g.
    // "cut to 4 of the 10 instruments to stay within 3000 moments"; empty when nothing was.
    std::string cut;
    // The zero-lag check (docs/measured-data.md, "The zero-lag check"), made when the defaults
    // chose the lagged equations for a record with every state measured: the zero-lag equations
    // with multipliers up to `degree` (their moments noise-corrected, save the channels inside
    // an abs or sign factor of the same moment), solved from the same pass, and Hotelling's test of
    // the difference of their estimate from the lagged one. The zero-lag equations weigh the tails
    // of the states' distribution, where a wrong law of damping or stiffness shows that the
    // lagged equations' instruments cannot see. `unavailable` says why there is no test.
    struct ZeroLagCheck {
      int degree = 0;
      std::size_t equations = 0;                // zero-lag equations taken
      std::vector<double> estimates;            // theirs, per parameter
      std::optional<double> statistic, pvalue;  // T^2, and its p-value from F(dof)
      std::pair<double, double> dof;
      std::string unavailable;
      // Rejected at 1%, which makes the result doubtful.
      bool rejects() const { return pvalue && *pvalue < 0.01; }
    };
    std::optional<ZeroLagCheck> zero_lag_check;
    // Per equation: the misfit taken out of its right-hand side (Integration::Misfit); empty
    // where none was.
    std::vector<double> misfit;
  };

  std::shared_ptr<const Model> model;
  std::string data_name;
  std::optional<ZeroLag> zero_lag;  // exactly one of the two is set
  std::optional<Lagged> lagged;
  DataMoments data;
  Estimate estimate;
  // Why these equations were taken (IdentifyOptions::method), e.g. "asked for".
  std::string why;
  // The optimally weighted estimate was asked for (SolveOptions::gmm: IdentifyOptions::weighting,
  // by default when the equations outnumber the free parameters); estimate.optimal says whether
  // it could be made.
  bool gmm = false;
  std::map<std::string, double>
      centered;  // the means removed, by variable (IdentifyOptions::center)
  // The states formed from a column of their derivative (IdentifyOptions::integrate).
  struct Integration {
    struct Formed {
      std::string state;
      std::string variable, column;  // the model's variable for the column, and the column
      int integrals = 0;             // 2 for y from a (y'' = a), 1 for v from it
      // The formed channel's noise variance per unit of the column's (both through the filter).
      double noise_gain = 0;
      // The equations hold it nonlinearly: their terms lose the low frequencies the filter cuts.
      bool cut = false;
    };
    std::vector<Formed> formed;
    // Where the equations hold a filtered state nonlinearly (a formed one, or a measured one in a
    // product with a formed one), the filter leaves a misfit: H(y^3) is not H(y)^3. It is read
    // off the same equations on the identified model's response to the recorded inputs, which
    // hold the estimates exactly and carry no sensor noise, and taken out of the record's
    // equations, which are then solved again (lagged.cpp; docs/model-language.md, "Forming a state
    // from its acceleration"). `rows`: the response's rows (the record's, up to a million);
    // `parameter` and `shift`: the estimate that moved most, by how many of its standard errors;
    // `failure`: why the response could not be had, the misfit then left in. Where the response's
    // spread is not the record's (a channel's standard deviation beyond 1.5 times the record's less
    // its noise, or below it divided by 1.5), the model does not reproduce the record, a doubt:
    // `channel` is the channel furthest off, `spread` its ratio.
    struct Misfit {
      std::size_t rows = 0;
      std::string parameter;
      double shift = 0;
      std::string failure;
      std::string channel;
      double spread = 1;
    };
    std::optional<Misfit> misfit;
    double corner = 0;  // Hz
    double dt = 0;      // the sample interval the filter is designed for
    bool corner_chosen = false;
    std::string band;        // how the corner was chosen, when it was
    std::size_t settle = 0;  // rows at the start of each run that fill the filter
    // Formed without IdentifyOptions::integrate: the equations needed the states (identify()).
    bool by_default = false;
  };
  std::optional<Integration> integration;
  // Where the record shows some states in no way (latent states, docs/latent-states.md): the
  // equations with them eliminated, whose coefficients the lagged pass estimated (lagged->system
  // reads coefficient_model), and the parameters found from the coefficients c by minimum
  // distance: the p that brings the coefficients f(p) nearest c in the metric of the inverse of
  // c's errors' batch covariance. `distance`, Q = r' (M V M')^+ r for the residual r = c - f(p),
  // V c's covariance and M V M' r's, tests the restrictions that the model puts on the
  // coefficients: chi-square on `dof` (coefficients less parameters).
  struct Latent {
    std::vector<std::string> states;
    std::string equations;  // the elimination, as `momentid derive` prints it
    std::shared_ptr<const Model> coefficient_model;
    std::vector<ParameterEstimate> coefficients;  // the main fit's, named by their expressions
    std::optional<double> distance, pvalue;
    int dof = 0;
    bool converged = false;
    // The search starts from the model's nominal values; where it does not converge there or
    // its Q is rejected at 1%, from `starts` more values around them (0: not needed), the
    // lowest converged Q taken. `nominal_distance` is Q from the nominal values then.
    int starts = 0;
    std::optional<double> nominal_distance;
  };
  std::optional<Latent> latent;
  // IdentifyOptions::refine: the refinement from the main estimate, of the parameters it
  // estimated (momentid/refine.hpp); null otherwise.
  std::shared_ptr<const RefineResult> refinement;
  // Why the refinement asked for could not run (its error's message), a doubt; empty otherwise.
  std::string refinement_failure;
  // The identified model runs away from its equilibrium (runaway()): a doubt.
  std::optional<Runaway> runaway;
  // The law check (docs/measured-data.md, "The law check"): for a damping term of quadratic
  // drag, abs(v)*v, or of Coulomb friction, sign(v) (v a velocity, y' = v), the model identified
  // again with the other law of the same state added to the equation, and that term's estimate
  // in standard errors. A doubt beyond kLawZ: the two laws are nearly collinear over a record,
  // and a wrong one leaves a residual that the J test sees weakly.
  struct LawCheck {
    std::string equation;  // the library target: "v'" or a label
    std::string term;      // "sign(v)", "abs(v)*v"
    double z = 0;          // its estimate over its standard error
  };
  std::vector<LawCheck> law_checks;
  static constexpr double kLawZ = 4;
  // The means of the channels read (after `centered` was removed), states then inputs.
  std::vector<ChannelMean> means;
  // The identified model's response to the recorded inputs, simulated when the offset check would
  // otherwise name a state's mean (docs/cli/identify.md, "Warnings"): per state with a column,
  // its mean and the response's over the same rows (each run's from where the simulation has
  // forgotten its start), and the standard error of their difference's mean from batches. A
  // periodic force such as a multisine gives a nonlinear model's states a mean of their own,
  // which the check then expects. Empty when nothing was simulated (no offset in doubt, an input
  // without a column, a simulation that blows up or does not follow the record).
  struct ResponseMean {
    std::string name;
    double recorded = 0, simulated = 0, std_error = 0;
  };
  std::vector<ResponseMean> response_means;
  // Why the response was simulated but gave no means (a simulation that does not follow the
  // record, an input without a column), or empty.
  std::string response_failure;

  // The main result: the optimally weighted estimate when it was asked for and could be
  // computed, otherwise least squares.
  const std::vector<ParameterEstimate>& parameters() const;
  // The zero-lag check, when one was planned (Lagged::zero_lag_check); null otherwise.
  const Lagged::ZeroLagCheck* zero_lag_check() const {
    return lagged && lagged->zero_lag_check ? &*lagged->zero_lag_check : nullptr;
  }
};

// Derives the moment equations of `model`, estimates the moments they need from `source` in one
// pass, and solves for the parameters. Throws UsageError for invalid options, ModelError,
// DataError or Error for a model or data that cannot be used. Poor or impossible answers are
// results: see Estimate::status.
//
// Example (model_file.hpp):
//   std::shared_ptr<const Model> model = load_model("models/duffing.mom");
//   IdentifyResult r = identify(*model, DataSource::file("duffing.csv"), {.degree = 3});
//   std::cout << format_text(r);
IdentifyResult identify(const Model& model, const DataSource& source,
                        const IdentifyOptions& options = {});

// The model's equations with the estimates (of parameters()) substituted, each solved for its
// derivative when it has one with a number in front (`v' = -0.500938*v - 4.00069*y + x`),
// otherwise with the derivative terms on the left; empty unless the status is ok or doubtful.
std::vector<std::string> identified_equations(const IdentifyResult& result);

// The identified model linearised at its equilibrium under the inputs' means (Newton from the
// origin), with the estimates of parameters(): the natural frequency (Hz, for time in seconds)
// and damping ratio of each oscillating mode (a complex pair of eigenvalues -zeta w +- i w
// sqrt(1 - zeta^2)), by frequency, with standard errors by the delta method over the main fit's
// covariance. No modes, with `unavailable` saying why, when the estimate is not usable, no
// equilibrium is found, an abs(...) or sign(...) term switches at it, or every eigenvalue is real.
struct LinearisedModes {
  struct Mode {
    double frequency_hz = 0, frequency_se = 0, damping_ratio = 0, damping_se = 0;
  };
  std::vector<double> equilibrium;  // per state
  std::vector<Mode> modes;
  std::string unavailable;
};
LinearisedModes linearised_modes(const IdentifyResult& result);

// The means that the inputs' means give the states of the identified model, to first order: its
// linearisation at the origin, x' = A x + B u, at rest, E[x] = G E[u] with G = -A^-1 B; `gain`
// holds G (a row per state, a column per input) to carry the inputs' standard errors. Empty
// when the estimate is not usable, the model has no input, A is singular or an abs(...) or
// sign(...) term switches at the origin.
struct MeanResponse {
  std::vector<double> mean;               // per state
  std::vector<std::vector<double>> gain;  // per state, per input
};
MeanResponse mean_response(const IdentifyResult& result);

// Whether the identified model runs away (Runaway, above); identify sets IdentifyResult::runaway
// from it.
std::optional<Runaway> runaway(const IdentifyResult& result);

// For an oscillator y' = v, m v' = -R(y) - ... + x with a constant mass m (two states): the
// restoring force R (m times minus the acceleration at rest, inputs at 0) at 41 displacements over
// the record's mean +- 3 standard deviations of y, and the backbone, the frequency (Hz) of free
// undamped oscillation about the equilibrium at 20 amplitudes up to 3 standard deviations by
// harmonic balance (NaN where the restoring force does not hold it), each with standard errors by
// the delta method. Empty, with `unavailable` saying why, for other models.
struct NonlinearCurves {
  std::string state;
  std::vector<double> displacement, force, force_se;
  std::vector<double> amplitude, frequency_hz, frequency_se;
  std::string unavailable;
};
NonlinearCurves nonlinear_curves(const IdentifyResult& result);
// Draws the restoring force and the backbone of nonlinear_curves with their 95% bands as SVG
// (docs/cli/identify.md, "The identified model"), written whole or not at all. Throws
// UsageError naming `plot` when the model has no such curves, with the reason.
void write_engineering_plot(const IdentifyResult& result, const std::string& path);

// A table (parameter, estimate, standard error, 95% interval), the identified model, then the
// diagnostics.
std::string format_text(const IdentifyResult& result);
// The JSON layout (docs/json.md, "identify").
std::string format_json(const IdentifyResult& result);
// What makes a result doubtful (docs/cli/identify.md, "Warnings"): a J test that rejects the model
// (p < 0.01), a zero-lag check that does, a law check beyond kLawZ, a stationarity identity
// violated (|z| > 4), a state with
// a mean of more than 0.2 of its standard deviation when the model is symmetric and its inputs have
// none, standard errors that rest on fewer than 10 degrees of freedom.
std::vector<std::string> doubts(const IdentifyResult& result);
// The solver's status; when it is kOk, kDoubtful when there are doubts, else kUntested when no
// J test was made.
Status status(const IdentifyResult& result);
// Every warning about the result, the most serious first: the solver's status, the doubts, an
// optimal weighting that could not be made, weakly determined parameters (standard error above
// 10% of the value) and strongly correlated pairs (|rho| > 0.95), then the data's smoothness and
// noise and the solver's other remarks.
std::vector<std::string> warnings(const IdentifyResult& result);

}  // namespace momentid
