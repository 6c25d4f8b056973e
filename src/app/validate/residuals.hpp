#pragma once
// The residual tests of validate: whether the simulation error is white, and whether it is
// independent of each input, each with its 99% band.

#include <cstddef>
#include <vector>

#include "momentid/validate.hpp"

namespace momentid {

// Sets fit.autocorrelation (lags 1..lags) and fit.cross (one per input with a spread, lags
// -lags..lags) from the error of the compared rows, run by run, after each run's `skip` rows;
// neither when the error is the same throughout (nothing to correlate). Uses fit.samples.
void add_correlation_checks(const Model& model, const Record& record,
                            const std::vector<std::size_t>& skip,
                            std::vector<std::vector<double>> error, int lags, OutputFit& fit);

}  // namespace momentid
