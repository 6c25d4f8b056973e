#include "solve/long_run.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <unsupported/Eigen/FFT>
#include <vector>

#include "solve/distributions.hpp"

namespace momentid {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// The first Fourier frequency fitted: j = 1 mixes, through the taper, with the removed mean.
constexpr Index kFirstOrdinate = 2;
constexpr int kMaxOrder = 4;

// Whittle fit of a moving average of order q to the periodogram `s` at frequencies `w`.
struct WhittleFit {
  int order = 0;
  double criterion = 0;
  MatrixXd design;  // ordinates x (q + 1): 1, 2 cos w, ..., 2 cos q w
  VectorXd weight;  // 1 / f^2 at the fitted spectrum
  VectorXd spectrum;
};

WhittleFit whittle(const VectorXd& s, const VectorXd& w, int q) {
  const Index m = s.size();
  WhittleFit fit{q, 0, MatrixXd(m, q + 1), VectorXd::Ones(m), VectorXd()};
  fit.design.col(0).setOnes();
  for (int h = 1; h <= q; ++h) fit.design.col(h) = 2 * (h * w.array()).cos();
  // A floor keeps the weights finite where a fit dips to zero.
  const double floor = 1e-3 * s.mean();
  for (int iteration = 0; iteration < 8; ++iteration) {
    const MatrixXd normal = fit.design.transpose() * fit.weight.asDiagonal() * fit.design;
    const VectorXd g = normal.ldlt().solve(fit.design.transpose() * fit.weight.cwiseProduct(s));
    fit.spectrum = (fit.design * g).cwiseMax(floor);
    fit.weight = fit.spectrum.cwiseAbs2().cwiseInverse();
  }
  // -2 log-likelihood of exponential ordinates, plus BIC's penalty.
  fit.criterion = 2 * (fit.spectrum.array().log() + s.array() / fit.spectrum.array()).sum() +
                  static_cast<double>(q + 1) * std::log(static_cast<double>(m));
  return fit;
}

}  // namespace

double LongRunCovariance::t975() const { return student_t_quantile(0.975, std::max(1.0, dof)); }

MatrixXd batch_covariance(const MatrixXd& batches) {
  const Index b = batches.rows();
  if (b < 2) return MatrixXd::Zero(batches.cols(), batches.cols());
  const MatrixXd x = batches.rowwise() - batches.colwise().mean();
  return x.transpose() * x / (static_cast<double>(b) * static_cast<double>(b - 1));
}

MatrixXd grouped_covariance(const MatrixXd& batches, Index groups) {
  const Index b = batches.rows();
  MatrixXd means(groups, batches.cols());
  for (Index k = 0; k < groups; ++k) {
    const Index from = k * b / groups, to = (k + 1) * b / groups;
    means.row(k) = batches.middleRows(from, to - from).colwise().mean();
  }
  return batch_covariance(means);
}

LongRunCovariance long_run_covariance(const MatrixXd& batches) {
  const Index b = batches.rows(), d = batches.cols();
  const auto bd = static_cast<double>(b);
  const Index last = (b - 1) / 2, m = last - kFirstOrdinate + 1;
  if (b < kMinSpectralBatches) {
    const MatrixXd s = batch_covariance(batches);
    return {s, s, std::max(0.0, bd - 1), 0};
  }

  // The Hann-tapered series and its periodogram: I_j = z_j z_j^*, E[I_j] ~ f(w_j).
  VectorXd taper(b);
  for (Index i = 0; i < b; ++i) {
    taper(i) = std::pow(std::sin(std::numbers::pi * (static_cast<double>(i) + 0.5) / bd), 2);
  }
  const double taper_power = taper.squaredNorm();
  const MatrixXd x = batches.rowwise() - batches.colwise().mean();
  Eigen::FFT<double> fft;
  Eigen::MatrixXcd z(m, d);
  std::vector<double> in(static_cast<std::size_t>(b));
  std::vector<std::complex<double>> out;
  for (Index c = 0; c < d; ++c) {
    for (Index i = 0; i < b; ++i) in[static_cast<std::size_t>(i)] = taper(i) * x(i, c);
    fft.fwd(out, in);
    for (Index j = 0; j < m; ++j) {
      z(j, c) = out[static_cast<std::size_t>(j + kFirstOrdinate)] / std::sqrt(taper_power);
    }
  }

  // The pilot: the columns standardised and averaged, one spectrum for the weights.
  const VectorXd power = z.cwiseAbs2().colwise().mean().transpose();
  VectorXd s = VectorXd::Zero(m);
  int used = 0;
  for (Index c = 0; c < d; ++c) {
    if (power(c) > 0) {
      s += z.col(c).cwiseAbs2() / power(c);
      ++used;
    }
  }
  if (used == 0) return {MatrixXd::Zero(d, d), MatrixXd::Zero(d, d), bd - 1, 0};
  s /= used;
  VectorXd w(m);
  for (Index j = 0; j < m; ++j) {
    w(j) = 2 * std::numbers::pi * static_cast<double>(j + kFirstOrdinate) / bd;
  }
  WhittleFit best;
  for (int q = 1; q <= kMaxOrder && 4 * (q + 1) <= m; ++q) {
    WhittleFit fit = whittle(s, w, q);
    if (best.order == 0 || fit.criterion < best.criterion) best = std::move(fit);
  }

  // The mean's covariance (g_0 + 2 sum (1 - h / B) g_h) / B, as weights on the ordinates.
  VectorXd target(best.order + 1);
  target(0) = 1;
  for (int h = 1; h <= best.order; ++h) target(h) = 2 * (1 - h / bd);
  const MatrixXd normal = best.design.transpose() * best.weight.asDiagonal() * best.design;
  const VectorXd kappa = best.weight.cwiseProduct(best.design * normal.ldlt().solve(target));
  const MatrixXd re = z.real(), im = z.imag();
  MatrixXd v =
      (re.transpose() * kappa.asDiagonal() * re + im.transpose() * kappa.asDiagonal() * im) / bd;
  v = (v + v.transpose()) / 2;
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(v);
  const MatrixXd clipped = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0).asDiagonal() *
                           eigen.eigenvectors().transpose();

  // Neighbouring tapered ordinates are correlated: rho_k = |sum h^2 e^{-i w_k t}| / sum h^2.
  const VectorXd kf = kappa.cwiseProduct(best.spectrum);
  double variance = kf.squaredNorm();
  for (Index k = 1; k <= 3 && k < m; ++k) {
    std::complex<double> sum = 0;
    for (Index i = 0; i < b; ++i) {
      sum += taper(i) * taper(i) *
             std::polar(1.0, -2 * std::numbers::pi * static_cast<double>(k * i) / bd);
    }
    const double rho = std::abs(sum) / taper_power;
    variance += 2 * rho * rho * kf.head(m - k).dot(kf.tail(m - k));
  }
  const double mean = kf.sum();
  return {clipped, v, variance > 0 ? 2 * mean * mean / variance : bd - 1, best.order};
}

}  // namespace momentid
