// The identified model's response to the recorded inputs, for the offset check
// (response_means.hpp).

#include "app/identify/response_means.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "app/identify/response_record.hpp"
#include "app/validate/record.hpp"
#include "app/validate/replay.hpp"
#include "common/number.hpp"
#include "momentid/validate.hpp"
#include "solve/long_run.hpp"

namespace momentid {
namespace {

// The simulation must follow the record: the root mean square of each state's error about its
// mean below this share of the state's standard deviation. A periodic force can give a nonlinear
// model several responses, and a chaotic one follows none: their means say nothing of this one.
constexpr double kFollowed = 0.5;
// The error's mean has a standard error from up to kBatches contiguous batches of at least
// kBatchRows rows (long_run_covariance, as the pass's means have theirs): a response that follows
// the record loosely (a chaotic stretch) carries a mean error of its own, which a periodic
// record's own mean, nearly the same in every batch, does not.
constexpr std::size_t kBatches = 100, kBatchRows = 50;

// The rows simulated, from the record's start: a constant offset shows in any stretch, and the
// record is held whole in memory.
constexpr std::size_t kMostRows = std::size_t{1} << 20;

// The mean of `recorded` and of the response (`recorded` less `error`), with the standard error of
// the error's mean from its batches. Throws Error when the response does not
// follow the record (kFollowed) or too few rows are left.
IdentifyResult::ResponseMean compare(const std::string& name, const std::vector<double>& recorded,
                                     const std::vector<double>& error) {
  const std::size_t rows = recorded.size(), batches = std::min(kBatches, rows / kBatchRows);
  if (batches < 2) {
    throw Error("the simulation leaves " + std::to_string(rows) + " rows of '" + name +
                "' to compare, fewer than " + std::to_string(2 * kBatchRows));
  }
  const auto mean_of = [](const std::vector<double>& x) {
    return std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
  };
  const double mean = mean_of(recorded), error_mean = mean_of(error);
  double variance = 0, error_variance = 0;
  for (std::size_t n = 0; n < rows; ++n) {
    variance += (recorded[n] - mean) * (recorded[n] - mean);
    error_variance += (error[n] - error_mean) * (error[n] - error_mean);
  }
  if (!(error_variance < kFollowed * kFollowed * variance)) {
    throw Error(
        "the simulation does not follow the record (the root mean square of the error in '" + name +
        "' is " + number(std::sqrt(error_variance / variance), "%.2g") +
        " of its standard deviation: another of a periodic force's responses, or chaos)");
  }
  // Row b: n_b / n (the batch's mean less the whole's), as long_run_covariance reads them.
  Eigen::MatrixXd deviations = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(batches), 1);
  const double per_batch = static_cast<double>(rows) / static_cast<double>(batches);
  for (std::size_t n = 0; n < rows; ++n) {
    deviations(static_cast<Eigen::Index>(n * batches / rows), 0) +=
        (error[n] - error_mean) / per_batch;
  }
  return IdentifyResult::ResponseMean{
      .name = name,
      .recorded = mean,
      .simulated = mean - error_mean,
      .std_error = std::sqrt(std::max(0.0, long_run_covariance(deviations).covariance(0, 0)))};
}

}  // namespace

void simulate_response_means(IdentifyResult& result, const DataSource& source,
                             const IdentifyOptions& options) {
  if (!result.estimate.usable() || !offset_in_doubt(result)) return;
  const Model& model = *result.model;
  const ReplayOptions replay_options = replay_at_estimates(result, options);
  std::vector<IdentifyResult::ResponseMean> out;
  try {
    Record record = read_record(model, source, replay_options, kMostRows);
    // The means the pass removed (--center), as it removed them.
    remove_means(model, record, result.centered);
    const Replay replay = replay_record(model, std::move(record), replay_options);
    const RecordSimulator simulator(model, replay_options.parameters, replay.interpolation,
                                    replay.record.dt, replay.substeps);
    const Record& read = replay.record;
    std::vector<std::size_t> skip;
    for (std::size_t r = 0; r < read.runs.size(); ++r) {
      skip.push_back(forgetting_row(simulator, run_inputs(model, read, read.runs[r]),
                                    replay.initial[r], replay.simulated[r], run_start(read.runs[r]),
                                    run_label(read, r))
                         .first);
    }
    for (std::size_t j = 0; j < model.states().size(); ++j) {
      const int column = read.column_of(j);
      if (column < 0) continue;
      std::vector<double> recorded, error;  // over the rows compared, run after run
      for (std::size_t r = 0; r < read.runs.size(); ++r) {
        const std::vector<double>& y = read.runs[r].columns[static_cast<std::size_t>(column)];
        const std::vector<double>& s = replay.simulated[r][j];
        for (std::size_t n = skip[r]; n < y.size(); ++n) {
          recorded.push_back(y[n]);
          error.push_back(y[n] - s[n]);
        }
      }
      out.push_back(compare(model.states()[j].name, recorded, error));
    }
  } catch (const Interrupted&) {
    throw;
  } catch (const Error& e) {
    // An input without a column, a simulation that blows up or strays: the check stands as it
    // was, and says what it could not see.
    result.response_failure = e.what();
    return;
  }
  result.response_means = std::move(out);
}

}  // namespace momentid
