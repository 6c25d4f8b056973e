#pragma once

// From a derived system and estimates named by their moments to the solver's own input:
// MomentRows over the moments of moments_to_estimate, and the estimates in that order.

#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "momentid/estimate.hpp"

namespace momentid {

// The terms (monomial, weight) of `m` with every power of a noisy variable replaced by its
// Hermite polynomial in the variance noise[v] of white Gaussian noise on it (absent or 0: none),
// y^3 by y^3 - 3 noise y^1: their expectation over the noise is that of the clean monomial. Every
// term is listed whatever the variances, zero weights too, so that the list can be made before
// the variances are known.
std::vector<std::pair<Monomial, double>> noise_corrected(const Monomial& m,
                                                         const std::vector<double>& noise);

// Per channel read (channel[u]: where variables()[u] is read, or -1), the channels its values
// are computed from, for an abs or sign of them (empty for a channel of the record). With
// channel[u] = u, over the model's variables.
std::vector<std::vector<std::size_t>> computed_from(const Model& model,
                                                    const std::vector<int>& channel);

// The noise variances by which to correct a monomial at one time: none for a channel that is
// also inside one of its abs or sign factors (`from`, of computed_from), whose noise no
// polynomial removes, so that the correction of its power would not be right either
// (E[(v + e)^2 sign(v + e)] is not E[v^2 sign(v)] plus a multiple of E[sign(v + e)]); the other
// channels' noise is independent of the factor and corrected as ever.
std::vector<double> correctable_noise(const Monomial& m, std::vector<double> noise,
                                      const std::vector<std::vector<std::size_t>>& from);

// Each moment's position in `moments`.
std::map<Monomial, std::size_t> positions(const std::vector<Monomial>& moments);

// The estimates of `wanted`, in that order, taken by key from `estimates` of `given` (one per
// entry of estimates.mean, in any order, possibly more than wanted). Throws std::invalid_argument
// when `given` does not name every estimate once, or lacks a wanted moment (named after
// `model`'s variables); `caller` opens the message.
MomentEstimates estimates_of(const std::vector<Monomial>& wanted,
                             const std::vector<Monomial>& given, const MomentEstimates& estimates,
                             const Model& model, const char* caller);

// A combination's weights over the moments at `index`, E[1] as the constant; nullopt when it
// holds a moment that `index` lacks.
std::optional<MomentRows::Entry> entry_of(const MomentCombination& combination,
                                          const std::map<Monomial, std::size_t>& index);

// The system's equations as MomentRows over the moments at `index` (every moment they use).
MomentRows moment_rows(const MomentSystem& system, const std::map<Monomial, std::size_t>& index);

}  // namespace momentid
