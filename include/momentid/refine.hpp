#pragma once
// The simulation-error refinement (docs/refine.md): the parameter values whose simulation through
// a record's inputs comes nearest the record's measured channels, found by nonlinear least
// squares (Ceres Solver's Levenberg-Marquardt) from a start, the moment estimate where there is
// one. Any model that validate can simulate can be refined, latent nonlinear states included.
//
// Example:
//   RefineOptions options;
//   options.start = identify(model, source).parameters();
//   RefineResult r = refine(model, source, options);

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "momentid/fit.hpp"
#include "momentid/model.hpp"
#include "momentid/reader.hpp"
#include "momentid/validate.hpp"

namespace momentid {

// How to refine (docs/cli/refine.md, "momentid refine").
struct RefineOptions {
  // The record, the interpolation of its inputs, the Runge-Kutta substeps (chosen at the start
  // values when not given) and the start values: by name, a parameter not given at its nominal
  // value. `start` overrides them.
  ReplayOptions replay;
  // A start with intervals, as identify estimated it: its values start the search, and a refined
  // value outside its 95% interval is reported as moved (RefinedParameter::moved). Fixed and
  // unidentifiable entries keep their values and are not refined.
  std::vector<ParameterEstimate> start;
  // The parameters refined; empty: those of `start` that it estimated, or without `start` every
  // parameter the model does not declare fixed.
  std::vector<std::string> free;
  // Rows left out at the start of each run; nullopt: until the simulation at the start values has
  // forgotten its initial state (as validate chooses them), where the segments' initial states
  // are taken from it.
  std::optional<std::size_t> skip;
  // States and inputs whose mean is removed from their columns first (ValidateOptions::center).
  std::vector<std::string> center;
  int max_iterations = 50;

  static constexpr int kMaxIterations = 10000;
  // The search stops when an iteration changes the cost, or the values, by less than this
  // fraction; the replicates that measure the inputs' noise's bias (below) stop sooner.
  static constexpr double kTolerance = 1e-12, kReplicateTolerance = 1e-9;
  // The refinements with the inputs' noise doubled that measure its bias, the most iterations
  // each takes from the refined values, and their first seed.
  static constexpr std::size_t kNoiseReplicates = 4;
  static constexpr int kReplicateIterations = 20;
  static constexpr std::uint64_t kNoiseSeed = 20261130;
  // The rows of a segment: each run is simulated in stretches of this many rows, each from an
  // initial state refined with the parameters (the last stretch of a run takes the remainder);
  // shorter, down to kMinSegmentRows, where the record would give fewer than kMinSegments, whose
  // spread gives the errors.
  static constexpr std::size_t kSegmentRows = 2000, kMinSegmentRows = 200, kMinSegments = 16;
  // Throws UsageError for a name in `free` that is not a parameter of `model`, or
  // `max_iterations` out of 1..kMaxIterations.
  void validate(const Model& model) const;
};

// A refined parameter beside its start.
struct RefinedParameter {
  std::string name;
  double start = 0;
  // The start's standard error and 95% interval (NaN: the start has none).
  double start_error = 0, start_low = 0, start_high = 0;
  // The refined value less the bias of the inputs' noise (noise_shift), and its errors, which
  // include the spread of the replicates that measured that bias.
  ParameterEstimate refined;
  // The bias that the inputs' white noise gives the fit (errors in variables), removed: how far
  // the fit moved when that noise was doubled (RefineResult::noise_replicates); 0 without noise.
  double noise_shift = 0;
  // The refined value lies outside the start's 95% interval.
  bool moved = false;
};

// A sampled input's (not held) white sensor noise, which drives the simulation with a force the
// system never felt and biases the refinement (errors in variables), and its band: where the noise
// dominates beyond the band's edge, the input the simulation reads is low-passed there
// (docs/refine.md, "Noise on the inputs").
struct InputBand {
  std::string input;
  std::size_t index = 0;        // among the model's inputs
  double noise_rms = 0;         // the white noise on the column
  double edge = 0, cutoff = 0;  // Hz: the gain falls from 1 at the edge to 0 at the cutoff
  bool filtered = false;

  static constexpr double kFloorRatio = 10;  // the band: where the spectrum exceeds the noise's
  static constexpr double kMaxCutoff = 0.8;  // of the Nyquist frequency: beyond, left as it is
};

// A measured channel's simulation error at the start and after the refinement.
struct RefinedOutput {
  std::string name;
  double rms_start = 0, rms = 0;
};

struct RefineResult {
  std::shared_ptr<const Model> model;
  std::string data_name;
  std::string start_from;  // "the moment estimate", "the model's nominal values", ...
  std::vector<RefinedParameter> parameters;     // the refined ones, in declaration order
  std::vector<std::vector<double>> covariance;  // of their refined values
  std::vector<RefinedOutput> outputs;           // the compared channels, in model order
  std::vector<InputBand> inputs;                // the sampled inputs (a held one is exact)
  std::size_t noise_replicates = 0;  // refinements that measured the inputs' noise's bias
  std::vector<std::size_t> skip;     // per run
  std::size_t segments = 0;          // simulated each from its own initial state
  std::size_t segment_rows = 0;      // their length (the last of a run takes the remainder)
  int substeps = 1;
  std::size_t samples = 0;  // residuals compared: rows after the skips times outputs
  // Half the sum of the squared errors, each channel's divided by its rms at the start (Ceres'
  // cost), before and after.
  double cost_start = 0, cost = 0;
  int iterations = 0;
  bool converged = false;
  std::string solver;  // the solver's own account of how it ended
  // Degrees of freedom of the intervals: the segments less one.
  double dof = 0;
  std::vector<std::string> warnings;

  // Whether some refined value lies outside the start's interval.
  bool moved() const;
};

// Simulates `model` through the record's inputs, in segments (RefineOptions::kSegmentRows) each
// from its own initial state, and minimises the error in the measured states and measured
// derivatives over the parameters refined and the segments' initial states. Standard errors are the
// sandwich of the error's Jacobian and the covariance of the segments' scores (the initial states
// profiled out), so that an error correlated in time (noise on the inputs, a model's own error)
// does not make them too narrow. Throws UsageError for invalid options, DataError for a record that
// cannot be compared, and Error when the simulation at the start blows up.
RefineResult refine(const Model& model, const DataSource& source, const RefineOptions& options);

// The refinement's section of a report: the table of parameters beside their start, the
// simulation error before and after, the search (identify --refine prints it too).
std::string refinement_text(const RefineResult& result);
std::string format_text(const RefineResult& result);
std::string format_json(const RefineResult& result);

}  // namespace momentid
