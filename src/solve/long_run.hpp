#pragma once

#include <Eigen/Dense>

namespace momentid {

// The covariance of a record's mean of a vector series, from the series' values over B
// contiguous batches of the record: row b of `batches` is n_b / n (x_b - x) with x_b the batch's
// mean over its n_b samples, n their average and x the record's mean, so that the rows sum to
// zero and batches of unequal length count by their length.
//
// Why not S / B, with S the sample covariance of the batch means: the moment conditions are time
// averages of derivatives plus noise. Without noise their sum over a stretch telescopes to its
// end values, neighbouring batch means are negatively correlated, and the record's mean varies
// like 1 / T^2 while S / B varies like 1 / (B T^2): it depends on the batch count. With noise the
// mean varies like 1 / T. Both regimes and their mixture have the batch-mean spectrum of a short
// moving average,
//   f(w) = g_0 + 2 g_1 cos w + ... + 2 g_q cos q w,      (g_h: autocovariances at lag h)
// and the mean's covariance is (g_0 + 2 sum_h (1 - h / B) g_h) / B. The g_h are fitted to the
// periodogram of the tapered batch series by Whittle's method (iteratively reweighted least
// squares; q from 1 to 4, chosen by BIC on the series standardised and summed), at the Fourier
// frequencies 2 pi j / B, j >= 2. The taper (Hann) removes the jump between the record's ends,
// which would otherwise leak the ends' difference into every frequency, and the lowest frequency
// it mixes with the removed mean is left out. The result is a fixed linear combination of the
// periodogram matrices with one weight per frequency, whatever the columns, so that a projection
// of the series gets the projection of the covariance; negative eigenvalues (from negative
// weights) are set to zero in `covariance`, not in `linear`.
struct LongRunCovariance {
  Eigen::MatrixXd covariance;  // of the record's mean
  // The same before negative eigenvalues are set to zero: unbiased where the moving average fits,
  // which `covariance` is not in a series with many directions of nearly no long-run variance
  // (each gets a positive part of its noise). What traces over many directions take (j_test).
  Eigen::MatrixXd linear;
  // Effective degrees of freedom of the estimate (Satterthwaite, with the correlation of
  // neighbouring tapered ordinates): what the t quantiles and the J test use.
  double dof = 0;
  int order = 0;  // q of the fitted moving average; 0: too few batches, S / B

  // The 97.5% quantile of Student's t at `dof`, for 95% intervals. Below one degree of freedom
  // the t law has no variance and its quantiles overflow: at least one is taken (identify warns
  // that such errors are rough).
  double t975() const;
};

// Fewer batches than this leave too few frequencies for the fit: S / B with B - 1 degrees of
// freedom, as if the batch means were independent.
inline constexpr Eigen::Index kMinSpectralBatches = 20;

LongRunCovariance long_run_covariance(const Eigen::MatrixXd& batches);

// S / B: the covariance of the mean of independent batch means, with B - 1 degrees of freedom.
// Precise but, for moment conditions without noise, too large by a factor near B: a weight for the
// optimally weighted estimate, whose own errors come from long_run_covariance.
Eigen::MatrixXd batch_covariance(const Eigen::MatrixXd& batches);

// The covariance of the mean from `groups` groups of consecutive batches (as even in size as the
// batches allow), as if the groups' means were independent: groups - 1 degrees of freedom, every
// batch weighed alike. The spectral estimate tapers the series' ends, which is what lets it see
// the nearly zero long-run variance of records without noise; a series whose variance one
// extreme batch near an end holds (a high power of a state in a large excursion) then looks
// far more certain than it is (observed: a third of the variance). Needs 2 <= groups <= batches.
Eigen::MatrixXd grouped_covariance(const Eigen::MatrixXd& batches, Eigen::Index groups);

}  // namespace momentid
