#pragma once
// The noise band of a reproducible trajectory: whether each output's error is what the record's
// noise and the parameters' uncertainty leave (NoiseBand).

#include <cstddef>
#include <vector>

#include "app/validate/fit.hpp"
#include "momentid/validate.hpp"

namespace momentid {

// The noise band of each output of `outputs` (fit.hpp), whose compared rows (after each run's
// `skip`) are `rows`: the record replayed NoiseBand::kSimulations times more with white noise of
// every sampled input's estimated noise variance added to its column (replays that blow up are
// left out; with fewer than half left the band is not compared), and, with a covariance, the
// outputs' sensitivities to `parameters` one standard error away (not compared when one of
// those blows up).
NoiseBand compare_noise_band(const Model& model, const ParameterValues& parameters,
                             const std::vector<std::vector<double>>& covariance,
                             const Replay& replay, const std::vector<std::size_t>& skip,
                             const std::vector<std::size_t>& outputs,
                             const std::vector<ComparedRows>& rows);

}  // namespace momentid
