#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "momentid/accumulator.hpp"
#include "momentid/derive.hpp"
#include "momentid/fit.hpp"
#include "momentid/lagged.hpp"
#include "momentid/types.hpp"

namespace momentid {

struct SolveOptions {
  bool gmm = false;
  // Per parameter: a value that makes it known, its terms moved to the right-hand side; empty,
  // or nullopt for a parameter: estimated.
  std::vector<std::optional<double>> fixed;
  // Each row divided by the length of its coefficients (at the estimated moments), so that
  // equations of different sizes count alike; the delta method takes these weights as fixed.
  bool normalise_rows = false;
  // With gmm: the weights taken a second time, at the first weighted estimate, and the errors
  // widened by what that estimate's errors bring through them (docs/uncertainty.md, "Optimal
  // weighting and the J test"). For the lagged equations, many and correlated, whose two-step
  // intervals were too narrow; the zero-lag equations keep the two-step weights, whose intervals
  // the calibration study measured.
  bool iterate_weights = false;
  // solve() only: the covariance of the record's rates of change (the system's rate moments,
  // rate_key, in the order of moments_to_estimate), known from elsewhere, which is added to the
  // errors (docs/uncertainty.md, "End values").
  std::vector<std::vector<double>> rate_covariance;
  // solve_rows() only: a variance per moment of the estimates, known from elsewhere (the
  // accuracy that the equations' discretization leaves, docs/measured-data.md, "The accuracy
  // floor"), added to the errors of its record mean; empty: none.
  std::vector<double> moment_variance;
};

// The moments solve() needs estimates of: the system's moments, then those its identities
// mention.
std::vector<Monomial> moments_to_estimate(const MomentSystem& system);

// The sample violation of each of the system's pure-data identities whose moments are all among
// `moments`, in standard errors. `moments` names the moment of each entry of `estimates` (its
// means and the columns of its batch means), in any order; identities that need other moments
// are left out. The checks are the same, to the last bit, whatever the order of the moments and
// whatever other moments they list. Throws std::invalid_argument when `moments` does not name
// every estimate once.
std::vector<IdentityCheck> check_identities(const MomentSystem& system,
                                            const std::vector<Monomial>& moments,
                                            const MomentEstimates& estimates);

// Solves A(mu) theta = b(mu) by least squares with scaled columns and a rank-revealing SVD, and
// estimates the parameters' covariance from the batch series of their first-order errors (delta
// method), with a long-run covariance that holds whether the moment conditions telescope (records
// without noise) or not (docs/uncertainty.md, "Batches").
//
// `moments` names the moment of each entry of `estimates` (its means and the columns of its batch
// means), in any order and possibly with moments the system does not need: solve takes each of
// moments_to_estimate(system) by its key, and the result is the same, to the last bit, whatever
// the order and the extra moments. Throws std::invalid_argument naming a moment it needs that
// `moments` lacks, or when `moments` does not name every estimate once.
//
// The record's rates of change (a system derived with DeriveOptions::rates) enter the estimate
// at 0, their stationary value, as the stationarity identities have it; their batch means enter
// the errors, so that the batch series no longer holds the ends of the batches, and the error
// that the record's own ends leave is added from options.rate_covariance. With no batch series
// for them (all 0) and no rate_covariance, the estimate and its errors are those of the system
// derived without rates.
//
// Example:
//   const std::vector<Monomial> moments = moments_to_estimate(system);
//   DataMoments data = moments_from_data(source, states, inputs, moments, {});
//   Estimate e = solve(system, moments, data.estimates, {.gmm = true});
Estimate solve(const MomentSystem& system, const std::vector<Monomial>& moments,
               const MomentEstimates& estimates, const SolveOptions& options = {});

// A linear system in the parameters whose entries are linear in estimated moments: row r reads
// sum over p of a[r][p] * theta_p = b[r], each entry a constant plus weighted moments (indices
// into the estimates). The zero-lag and the lagged moment equations both come to this.
struct MomentRows {
  struct Entry {
    double constant = 0;
    std::vector<std::pair<std::size_t, double>> moments;  // (index, weight)
  };
  std::vector<std::vector<Entry>> a;  // rows x parameters
  std::vector<Entry> b;
};

// Solves `rows` as solve() does, for parameters named `names`: one per coefficient of every
// row. The rows' entries index the moments of `estimates` (its means and the columns of its
// batch means); SolveOptions::rate_covariance is not read. Throws std::invalid_argument when a
// row has not one coefficient per name or an entry indexes no estimate.
Estimate solve_rows(const MomentRows& rows, const std::vector<std::string>& names,
                    const MomentEstimates& estimates, const SolveOptions& options = {});

// The numbers behind lagged moment equations for data sampled every `dt`: one row per test
// function and equation, whose entries are lagged moments weighted by the test function (its
// derivatives for the lag derivatives, by parts), and the moments, over accumulator channels:
// `channel[v]` is model variable v's channel, or -1 for a variable the data lack. `stencil`:
// the reach of the lag-derivative stencils (stencil_weights). `noise[c]` is the variance of white
// noise on channel c (absent or 0: none); every power of a noisy channel is replaced by its Hermite
// polynomial in that variance (y^3 by y^3 - 3 v y), whose expectation over the noise is the clean
// power. The list of moments does not depend on the variances.
//
// `shared` (moment.hpp; empty without a filter): the noise that channels share across lags, taken
// out of each moment. The moments it adds are listed whatever the variances.
//
// `products`: monomials over the channels (as many entries as the model has variables or the
// channels count, whichever is more) read from a channel of their own, each where a function's
// term (after its noise correction) is that monomial: a product that a filter saw whole.
struct LaggedRows {
  std::vector<Moment> moments;
  MomentRows rows;
};
LaggedRows lagged_rows(const LaggedSystem& system, double dt, const std::vector<int>& channel,
                       const std::vector<double>& noise, int stencil = kStencilReach,
                       const SharedNoise& shared = {},
                       const std::map<Monomial, int>& products = {});

}  // namespace momentid
