#pragma once

// The channels and options of a pass over the record, as the steps of identify() ask for it.

#include <map>
#include <string>
#include <vector>

#include "momentid/data_pass.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {

// The state and input names of `model`, in declaration order: the channels of a zero-lag pass.
std::vector<std::string> state_names(const Model& model);
std::vector<std::string> input_names(const Model& model);
// The names of the columns that hold derivatives (Model::measured_derivatives()).
std::vector<std::string> derivative_names(const Model& model);

// The model's abs and sign terms as channels the pass computes; throws ModelError at an equation
// whose function mixes states and inputs.
std::vector<ComputedChannel> computed_channels(const Model& model);

// The options of a pass over the record as `options` ask for it (columns, sample interval,
// layout, input hold, batches, threads), with the autocorrelations the noise estimates need.
DataOptions pass_options(const Model& model, const IdentifyOptions& options);

// The offsets of DataOptions for the channels `states`, `inputs`, then options.derivatives: the
// mean of each channel that `center` names, and of each derivative column (whose true mean is 0,
// so that its mean is an offset) unless options.integration filters every channel, from a pass
// of its own, and 0 for the others; none when no channel is centered. Records the means removed
// in `centered`.
std::vector<double> channel_offsets(const DataSource& source,
                                    const std::vector<std::string>& states,
                                    const std::vector<std::string>& inputs,
                                    const DataOptions& options,
                                    const std::vector<std::string>& center,
                                    std::map<std::string, double>& centered);

}  // namespace momentid
