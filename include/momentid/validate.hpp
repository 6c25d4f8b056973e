#pragma once

#include <ginac/ginac.h>

#include <algorithm>
#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "momentid/metadata.hpp"
#include "momentid/model.hpp"
#include "momentid/parameters.hpp"
#include "momentid/reader.hpp"
#include "momentid/record_options.hpp"
#include "momentid/simulate.hpp"
#include "momentid/writer.hpp"

namespace momentid {

// A record in memory, run by run: the `t` column and the columns of the model's variables that
// the data have, for driving a model with its inputs (`validate`, `simulate --input-file`).
struct RecordRun {
  long number = 0;                           // the `run` column's value, 0 without one
  std::vector<double> time;                  // the `t` column; empty without one
  std::vector<std::vector<double>> columns;  // one per Record::variables entry
  std::size_t rows() const { return columns.empty() ? time.size() : columns.front().size(); }
};
struct Record {
  std::string name;
  std::vector<std::size_t> variables;  // the model variables the data have: states, then inputs
  std::vector<std::string> columns;    // their names in the data, in the same order
  bool has_time = false, has_run = false;
  double dt = 0;
  DataMetadata metadata;
  std::vector<RecordRun> runs;
  MissingSummary missing;  // rows dropped for missing values
  // The index in `variables` of model variable v, or -1.
  int column_of(std::size_t v) const;
};

// How to drive a model with a record's inputs (docs/cli/validate.md, "momentid validate").
struct ReplayOptions {
  // The record's columns, sample interval, layout and input hold (`hold` chooses the
  // interpolation below). `control` is ignored: the record is read once, whole.
  RecordOptions record;
  // By name; a parameter not given takes its nominal value.
  ParameterValues parameters;
  // nullopt: per input, kHold when it was held (record.hold, else the metadata's
  // `input-hold=zoh`), else kSinc.
  std::optional<Interpolation> interpolation;
  // Runge-Kutta steps per sample interval, 1..RecordSimulator::kMaxSubsteps; nullopt: the fewest
  // (1, 2, 4, ...) for which halving the step changes the simulation of the first
  // kSubstepTrialRows rows of the first run by less than kSubstepTolerance of each state's
  // spread.
  std::optional<int> substeps;

  static constexpr std::size_t kSubstepTrialRows = 4000;
  static constexpr double kSubstepTolerance = 1e-6;
};

// A record and the model's response to its inputs, run by run. Each run starts from its own
// initial state: a state with a column from its first sample; a state the data show as a
// derivative (v when y' = v) from the derivative at the start of a cubic fitted by least squares
// to the first kStartSamples samples; any other state from 0.
struct Replay {
  Record record;
  std::vector<Interpolation> interpolation;  // per model input
  int substeps = 1;
  // Held inputs put kinks into the states at the samples (the noise estimate's two forms).
  bool holds_an_input() const {
    return std::find(interpolation.begin(), interpolation.end(), Interpolation::kHold) !=
           interpolation.end();
  }
  bool substeps_chosen = false;
  // Chosen: how much halving the step changed the trial simulation (relative to each state's
  // spread); at least ReplayOptions::kSubstepTolerance when even the most substeps fell short.
  double substep_change = 0;
  std::vector<std::string> initial_how;      // per state, how its initial value was found
  std::vector<std::vector<double>> initial;  // per run, per state
  // simulated[r][j][n]: state j at row n of run r.
  std::vector<std::vector<std::vector<double>>> simulated;
  // derivatives[r][i][n]: measured derivative i (Model::measured_derivatives()) at row n of run
  // r, from the equations along the simulation.
  std::vector<std::vector<std::vector<double>>> derivatives;

  static constexpr std::size_t kStartSamples = 7;
};

// A record's series as one array each, every run's rows one run after the other (what a front
// end hands its users): the sample times (n*dt without a `t` column), the runs' numbers (1, 2,
// ... without a `run` column), model variable v as recorded (the record has it:
// Record::column_of(v) >= 0), and state j as a replay simulated it.
std::vector<double> series_times(const Record& record);
std::vector<double> series_runs(const Record& record);
std::vector<double> series_recorded(const Record& record, std::size_t v);
std::vector<double> series_simulated(const Replay& replay, std::size_t j);

// Reads the record and simulates the model through its inputs. Throws UsageError for invalid
// options, DataError for a record that lacks an input or gives no sample interval, and Error
// naming the time, run and state when the simulation blows up.
Replay replay(const Model& model, const DataSource& source, const ReplayOptions& options);

// Writes the replay in the record's layout (`simulate --input-file`): its `t` column, the columns
// of the model's variables it has, with the states replaced by the simulated ones, and its `run`
// column; in `format` (simulation_format() tells it from the name), whole or not at all (see
// DataWriter). Returns, for a .npy file, DataWriter::note().
std::vector<std::string> write_replay(const Model& model, const Replay& replay,
                                      const std::string& path, DataWriter::Format format);

// What an `identify --format json` result says of the parameters: one value per model
// parameter, by name, and their covariance matrix in declaration order (NaN where the file has
// null, an unknown error; empty when it has none).
struct Estimates {
  ParameterValues values;
  std::vector<std::vector<double>> covariance;
};

// Throws DataError located in the file for text that is not JSON, estimates of another model, a
// parameter missing or without a numeric estimate, or a covariance that is not a square array
// with a row per parameter.
Estimates read_estimates(const Model& model, const std::string& path);

// How to validate (docs/cli/validate.md, "momentid validate").
struct ValidateOptions {
  ReplayOptions replay;
  // Rows left out at the start of each run; nullopt: until the model has forgotten its initial
  // state (see ValidateResult::skip).
  std::optional<std::size_t> skip;
  // Lags of the correlation checks: 1..lags for the error's autocorrelation, -lags..lags for its
  // cross-correlation with each input.
  int lags = 25;
  // States and inputs whose mean (over the whole record) is removed from their columns before
  // the simulation and the comparison: a sensor's offset on a symmetric system, as
  // IdentifyOptions::center. A variable the record has no column for is left as it is.
  std::vector<std::string> center;
  // The covariance of the parameter values simulated with (Estimates::covariance), in
  // declaration order: it widens the noise band by the errors it gives the trajectory. Empty,
  // or with an entry that is not finite (an unknown error): the values are taken as exact.
  std::vector<std::vector<double>> covariance;

  static constexpr int kMaxLags = 1000;
  void validate() const;
};

// A correlation function of the simulation error with its 99% band: values at lags first_lag,
// first_lag + 1, ... Under the hypothesis that the error is white (autocorrelation) or
// independent of the input (cross-correlation; Bartlett's variance from both series'
// autocorrelations), 1% of the values fall outside +-band.
struct CorrelationCheck {
  std::string with;  // the input's name, empty for the autocorrelation
  int first_lag = 0;
  std::vector<double> values;
  double band = 0;
  std::size_t outside() const;
};

// How well one measured state is reproduced, over the rows compared (all runs, after the skip).
struct OutputFit {
  std::string name;
  // Its index among the outputs: the model's states, then its measured derivatives.
  std::size_t state = 0;
  std::size_t samples = 0;
  double rms = 0;  // root mean square of measured - simulated
  // 100 (1 - |y - y_sim| / |y - mean(y)|): 100 for a perfect reproduction, 0 for the mean.
  double fit = 0;
  double rms_start = 0;  // over the first 10% of each run's compared rows
  double rms_rest = 0;   // over the rest
  // Empty when the error is zero throughout (nothing to correlate).
  std::optional<CorrelationCheck> autocorrelation;
  std::vector<CorrelationCheck> cross;
};

// Output j of a model (OutputFit::state: its states, then its measured derivatives) as an index
// into Model::variables().
std::size_t output_variable(const Model& model, std::size_t j);

// How fast two simulations of the model under the record's input separate when one starts
// from the initial state perturbed by kPerturbation of each state's spread (docs/cli/validate.md,
// "Sensitivity"). The separation is the root mean square over the states of their differences,
// each in units of the state's spread; measured over every run, reported for the run where it
// grew most.
struct Sensitivity {
  std::size_t run = 0;          // the run's label
  double separation = 0;        // the largest separation reached within the run
  double final_separation = 0;  // at the run's end
  // Seconds from the run's start until the separation first reached kSpread; nullopt: never.
  std::optional<double> time_to_spread;
  // The finite-time largest Lyapunov exponent (1/s): ln(separation / kPerturbation) / T at
  // T = time_to_spread; when the separation never reached kSpread, at the run's end or where
  // it first fell below 1e-6 of its start (before rounding blurs it).
  double lyapunov = 0;
  // The separation reached kSpread within the record: the trajectory cannot be reproduced, and
  // the statistics judge the model instead.
  bool sensitive = false;

  static constexpr double kPerturbation = 1e-6, kSpread = 0.1;
};

// One statistic of one measured state compared with the same statistic of kRuns simulations
// (StatisticalValidation). `distance` is how far the record's statistic is from the runs' mean,
// `run_distances` each run's from the mean of the others; the band is 0..limit, from the runs'
// distances (docs/cli/validate.md, "Statistics").
struct StatisticCheck {
  std::string output;  // the output's name (a state, or a measured derivative)
  std::string kind;    // "psd", "distribution", "crossings", "prediction" or "bias"
  // The statistic at `at` (frequencies in Hz, probabilities, levels, for "prediction" the time
  // ahead in s, where the statistic is the rms prediction error, and for "bias" the index of each
  // state, where it is the slope of the prediction error at that time ahead on the state's
  // prediction, in units of the two states' spreads): the record's, and the runs' mean, smallest
  // and largest.
  std::vector<double> at, measured, mean, low, high;
  double distance = 0;
  std::vector<double> run_distances;
  double limit = 0;
  // "prediction": the constant sensor offset taken from the record's state before its prediction
  // error is measured (the runs' own are fitted alike), in units of the state's spread.
  double offset = 0;
  bool inside() const { return distance <= limit; }
};

// The response's statistics, measured against simulations of the model driven by the record's
// input from kRuns initial states that the model itself visits (its replay's states at rows
// spread over each run), each with the record's estimated white sensor noise added.
struct StatisticalValidation {
  bool compared = false;
  std::string not_compared;  // why not, when not compared
  std::size_t runs = 0;
  std::size_t segment = 0;       // Welch segment length in samples (Hann window, half overlap)
  double level = 0;              // the probability that every statistic of a right model is inside
  std::vector<double> noise_sd;  // per output compared, the noise added to the simulations
  std::vector<StatisticCheck> checks;
  std::size_t outside() const;

  static constexpr std::size_t kRuns = 12;
  static constexpr std::size_t kMinSegment = 64, kMaxSegment = 1024, kMinSegments = 8;
  static constexpr double kLevel = 0.99;
};

// Whether a reproducible trajectory's error is what the record's noise and the parameters'
// uncertainty leave (docs/cli/validate.md, "Noise band"). Per output, the error's smooth mean
// square (the median over segments of its mean square, less its white noise's variance, which
// the autocorrelation shows) is compared with a limit from two sources: kSimulations replays
// with white noise of each sampled input's estimated variance added to the input (each with white
// noise of the error's own white variance added, so that their smooth parts are estimated
// alike), whose prediction bound for one more (on a logarithmic scale when all are positive),
// at least kFloor of the output's spread squared, is the noise's share; and, with
// ValidateOptions::covariance, the quantile of the mean square that the estimates' errors leave
// (from the output's sensitivities to the parameters). The limit is the root of their sum, at
// kLevel for all outputs together; the figures are rms.
struct NoiseBand {
  struct Output {
    std::string name;
    double error = 0;                 // the record's error beyond its white noise (rms)
    std::vector<double> simulations;  // the same of each replay's difference from the first
    double estimates = 0;             // the estimates' errors' share of the limit (0 without)
    double limit = 0;
    bool inside() const { return error <= limit; }
  };
  bool compared = false;
  std::string not_compared;         // why not, when not compared
  std::vector<double> input_noise;  // per model input, the noise's standard deviation added
  bool with_errors = false;         // the estimates' covariance widened the limits
  double level = 0;                 // the probability that every output of a right model is inside
  std::vector<Output> outputs;
  std::size_t outside() const;

  static constexpr std::size_t kSimulations = 8;
  static constexpr double kFloor = 1e-3;
  static constexpr double kLevel = 0.99;
};

struct ValidateResult {
  std::shared_ptr<const Model> model;
  // Every parameter's value, by name: `value` the double nearest to the one simulated with (the
  // given one, else the nominal one), `decimal` the decimal given, if one was.
  ParameterValues parameters;
  std::string parameters_from;  // "the model's nominal values", a file name, ...
  Replay replay;
  // Rows left out at the start of each run. Chosen (skip_chosen): the first row after which a
  // perturbation of the initial state by 10% of each state's spread stays below 1% of its size
  // in the simulation, searched over the first half of the run; none for a model without
  // inputs, whose response is that to its initial state.
  std::vector<std::size_t> skip;
  bool skip_chosen = false;
  // The means removed (ValidateOptions::center), by variable.
  std::map<std::string, double> centered;
  std::vector<OutputFit> outputs;  // the measured states, in model order
  Sensitivity sensitivity;
  // Compared when the model is sensitive, or when its reproducible trajectory fails (to show
  // where the response differs); otherwise the trajectory judges the model alone.
  StatisticalValidation statistics;
  // Compared when the model is not sensitive: whether each output's error is what the noise
  // leaves.
  NoiseBand noise_band;
  // Sensitive: every statistic inside its band. Otherwise: every output inside its noise band,
  // none with a fit below 0%, none drifting beyond its band (the warnings say which).
  bool consistent = true;
  std::string verdict;  // one sentence: what judged the model, and what it found
  std::vector<std::string> warnings;
};

// Simulates the model through the record's inputs and compares the states the record has.
// Throws as replay(), UsageError for a name in `center` that is no state or input of the model,
// and DataError when a run has no row left to compare after the skip.
ValidateResult validate(const Model& model, const DataSource& source,
                        const ValidateOptions& options);

std::string format_text(const ValidateResult& result);
// The JSON layout (docs/json.md, "validate").
std::string format_json(const ValidateResult& result);

// Draws the comparison as SVG (docs/cli/validate.md, "Plot"): per output, the measured and
// simulated series over the window [from, to] (times; nullopt: the first 2000 compared rows of the
// first run) and their difference below; then the correlation checks with their bands, and the
// statistics (when compared) against the runs' range. Written whole or not at all. Throws
// UsageError for a window that holds no compared row.
void write_plot(const ValidateResult& result, const std::string& path,
                std::optional<std::pair<double, double>> window = std::nullopt);

}  // namespace momentid
