#pragma once

// The channels' means and their standard errors (IdentifyResult::means).

#include <cstddef>
#include <string>
#include <vector>

#include "momentid/data_pass.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {

// The first moments E[c] of `channels` channels, as monomials over them (over `variables`
// variables when more, such as a model's functions after its channels), in channel order.
std::vector<Monomial> first_moments_of(std::size_t channels, std::size_t variables = 0);

// Per channel `names[c]`: its mean, the estimate all.mean[index[c]], with the standard error from
// the long-run covariance of its batch series; empty with fewer than two batches.
std::vector<ChannelMean> channel_means(const std::vector<std::string>& names,
                                       const MomentEstimates& all,
                                       const std::vector<std::size_t>& index);

// Adds to the standard error of the mean of each state w that a kinematic equation makes another
// state's derivative (v in y' = v) the error of the record's ends: its mean over a run is
// (y(end) - y(start)) / (ratio T), whose batch series telescopes, so that the batches show
// nearly none of it; the ends, far apart, are independent draws of y, 2 runs Var(y) /
// (ratio T)^2 over the runs. The same for a column of a state's derivative (a = v'), with the
// variance of v from its channel or, when the record shows v only as y' (y' = v), from the
// differences of y. Needs the sample interval; `data` holds the channels' statistics.
void add_end_errors(std::vector<ChannelMean>& means, const Model& model, const DataMoments& data);

}  // namespace momentid
