#pragma once
// The statistics of a response that validate compares when a trajectory cannot be reproduced:
// the power spectral density (Welch), the amplitude quantiles and the level up-crossing rates.
// Each takes a series run by run (a series never spans two runs).

#include <cstddef>
#include <vector>

namespace momentid {

// One-sided power spectral density by Welch's method: Hann-windowed segments of `segment`
// samples (a power of two), overlapping by half, each with its mean removed; the periodograms
// averaged over every segment of every run. Density per Hz at frequencies k/(segment dt),
// k = 0..segment/2, so that its sum times the frequency step is the series' variance (up to
// the window's leakage). Runs shorter than a segment contribute nothing.
//
// Example: white noise of variance s2 sampled every dt has a density of 2 s2 dt.
std::vector<double> welch_psd(const std::vector<std::vector<double>>& runs, double dt,
                              std::size_t segment);

// The frequencies of welch_psd's values, in Hz.
std::vector<double> psd_frequencies(double dt, std::size_t segment);

// The p-quantiles of every run's values together, for each p in `probabilities` (linear
// interpolation between order statistics, as numpy's default).
std::vector<double> quantiles(const std::vector<std::vector<double>>& runs,
                              const std::vector<double>& probabilities);

// Up-crossings per second of each level: passages from below level - hysteresis to above
// level + hysteresis, so that noise around a level does not count as many crossings.
std::vector<double> upcrossing_rates(const std::vector<std::vector<double>>& runs, double dt,
                                     const std::vector<double>& levels, double hysteresis);

// The mean and standard deviation of every run's values together.
std::pair<double, double> mean_and_spread(const std::vector<std::vector<double>>& runs);

// The variance of white noise on a series that is smooth apart from it, as identify estimates
// it (data_pass.hpp): the mean square of its sixth difference, or for a series driven by inputs
// `held` over each sample the excess of its lag-0 autocovariance over held_lag_zero's
// extrapolation; 0 when the estimate is not positive.
double white_noise_variance(const std::vector<std::vector<double>>& runs, bool held);

// A prediction bound for one more of `values` (at least two), at `t` (Student's t at the level,
// values.size() - 1 degrees of freedom): on a logarithmic scale when every value is positive
// (distances, and effects that come in bursts, are skewed), else on a linear one (where the
// estimation of white noise dominates, symmetric about 0).
double prediction_bound(const std::vector<double>& values, double t);

}  // namespace momentid
