#pragma once

// Lists of moments: what a pass reads for a list of monomials, and parts of its estimates.

#include <cstddef>
#include <map>
#include <vector>

#include "momentid/data_pass.hpp"
#include "momentid/model.hpp"

namespace momentid {

// The moments the pass reads for `moments` (over the model's variables): a rate of change
// (Monomial::rate()) as the increment of its monomial.
std::vector<Moment> pass_moments_of(const std::vector<Monomial>& moments);

// `moments` without the rates of change.
std::vector<Monomial> without_rates(std::vector<Monomial> moments);

// The products g_i * g_j of the monomials `g` (i <= j), with the g themselves.
std::vector<Monomial> with_products(const std::vector<Monomial>& g);

// Each of `moments` with its position in the list.
std::map<Moment, std::size_t> moment_index(const std::vector<Moment>& moments);

// The moments of `all` at `index`, in that order, overall and per batch.
MomentEstimates moments_at(const MomentEstimates& all, const std::vector<std::size_t>& index);

// The first `count` moments of `all`, overall and per batch.
MomentEstimates first_moments(const MomentEstimates& all, std::size_t count);

// Those of `more` that are neither among `moments` nor the constant 1, each once, in their order.
std::vector<Monomial> not_among(const std::vector<Monomial>& moments,
                                const std::vector<Monomial>& more);

}  // namespace momentid
