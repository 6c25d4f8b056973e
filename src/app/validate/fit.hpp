#pragma once
// How well the simulation reproduces one measured state: its error over the compared rows and
// the statistics of the fit.

#include <cstddef>
#include <vector>

#include "momentid/validate.hpp"

namespace momentid {

// A measured state and its simulation over the compared rows (after each run's skip), run by
// run.
struct ComparedRows {
  std::vector<std::vector<double>> error;     // measured - simulated
  std::vector<std::vector<double>> measured;  // the state's column
};

// The outputs the record has: its states, then its measured derivatives, in model order;
// DataError when it has none.
std::vector<std::size_t> measured_outputs(const Model& model, const Record& record);

// Output j in run r as the replay simulated it.
const std::vector<double>& simulated_output(const Model& model, const Replay& replay, std::size_t r,
                                            std::size_t j);

// The compared rows of output `output` (which the record has) in every run after `skip` rows.
ComparedRows compared_rows(const Model& model, const Replay& replay, std::size_t output,
                           const std::vector<std::size_t>& skip);

// The fit of output `output` over `rows`: its samples, rms errors and fit %, without the
// correlation checks (residuals.hpp).
OutputFit output_fit(const Model& model, std::size_t output, const ComparedRows& rows);

// The warnings about a fit: worse than the data's mean, or an error that grows along the record
// unless `noise_explains` it (the output is inside its noise band: the noise's effect comes in
// bursts). Returns whether it warned.
bool add_fit_warnings(const OutputFit& fit, bool noise_explains,
                      std::vector<std::string>& warnings);

}  // namespace momentid
