#pragma once
// The law check of a model with a non-smooth damping law (IdentifyResult::law_checks).

#include <functional>

#include "momentid/identify.hpp"

namespace momentid {

// For each term c*abs(v)*v or c*sign(v) of `result.model` (v a velocity: y' = v), the
// model with the other law of v added as a library term, identified by `identify_model` (on the
// same record, with the same options), and the added term's estimate in standard errors, into
// result.law_checks. Nothing where the model has no such term, or where `options` name
// monomials of the model's variables (instruments, multipliers), which the extended model
// numbers otherwise.
void check_laws(IdentifyResult& result, const IdentifyOptions& options,
                const std::function<IdentifyResult(const Model&)>& identify_model);

}  // namespace momentid
