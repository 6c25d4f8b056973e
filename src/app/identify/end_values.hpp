#pragma once

// The record's ends: the rates of change E[(g)'] that the zero-lag equations keep, and their
// covariance (docs/uncertainty.md, "End values").

#include <cstddef>
#include <optional>
#include <vector>

#include "momentid/data_pass.hpp"
#include "momentid/model.hpp"

namespace momentid {

// The monomials g of the rates of change E[(g)'] among `moments`, in their order.
std::vector<Monomial> rate_monomials(const std::vector<Monomial>& moments);

// Turns the averages of the increments among `moments` (pass_moments_of) into the record's rates
// of change, dividing by the interval `interval` between the rows the pass read; without it, sets
// them to 0 (their stationary value) in every batch.
void increments_to_rates(const std::vector<Monomial>& moments, std::optional<double> interval,
                         MomentEstimates& estimates);

// The covariance of the record's rates of change (g(end) - g(start)) / T summed over its runs,
// for the monomials `g`, from `means`, those of with_products(g) in its order: each run's ends,
// far apart, are independent draws of the stationary states, so that the covariance is
// 2 runs Cov(g_i, g_j) / T^2 (docs/uncertainty.md, "End values").
std::vector<std::vector<double>> rate_covariance(const std::vector<Monomial>& g,
                                                 const std::vector<double>& means, std::size_t runs,
                                                 double duration);

}  // namespace momentid
