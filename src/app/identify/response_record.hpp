#pragma once
// The identified model's response to the recorded inputs as a record of its own, and the misfit
// that the filter forming states leaves in the lagged equations, read off the response's
// equations (lagged.cpp, "take_out_filter_misfit").

#include <cstddef>
#include <string>
#include <vector>

#include "momentid/data_pass.hpp"
#include "momentid/estimate.hpp"
#include "momentid/identify.hpp"
#include "momentid/reader.hpp"
#include "momentid/validate.hpp"

namespace momentid {

// How the model at the result's estimates replays the record identify read.
ReplayOptions replay_at_estimates(const IdentifyResult& result, const IdentifyOptions& options);

// The model at the result's estimates simulated through the inputs of the first `most_rows`
// rows of `source` (less the means the pass removed, as validate reads them): a record of the
// same rows and runs with a column per model variable the source has, named after the variable
// (a state as simulated, an input as recorded, a measured derivative from the equations along
// the simulation), without noise. Throws Error where the response cannot be had (an input
// without a column, a simulation that blows up).
class ResponseRecord {
 public:
  ResponseRecord(const IdentifyResult& result, const DataSource& source,
                 const IdentifyOptions& options, std::size_t most_rows);
  ResponseRecord(const ResponseRecord&) = delete;
  ResponseRecord& operator=(const ResponseRecord&) = delete;

  // Reads the arrays held here: valid while this lives.
  DataSource source() const;
  std::size_t rows() const { return data_.rows; }

 private:
  std::vector<std::vector<double>> columns_;
  MemoryData data_;
};

// The residual of the equations `rows` (noise-free, over the moments result.lagged->moments) on
// the response to the first million rows of `source`, read by a pass with `data_options` (its
// record and offsets replaced: the response's columns are named after the model's variables) over
// the channels `states` and `inputs`, at the estimates the response holds: one value per row.
// Empty where the response does not follow the record (a state or derivative channel whose
// standard deviation lies beyond 1.5 times the record's less its noise, or below it divided by
// 1.5): then misfit.channel, misfit.spread and misfit.failure say so. Sets misfit.rows. Throws
// Error where the response cannot be had.
std::vector<double> response_residual(const IdentifyResult& result, const LaggedRows& rows,
                                      const DataSource& source, const IdentifyOptions& options,
                                      DataOptions data_options,
                                      const std::vector<std::string>& states,
                                      const std::vector<std::string>& inputs,
                                      IdentifyResult::Integration::Misfit& misfit);

}  // namespace momentid
