#include "app/refine/input_band.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <unsupported/Eigen/FFT>

#include "app/validate/series_statistics.hpp"

namespace momentid {

InputBand input_band(const std::string& name, const std::vector<std::vector<double>>& runs,
                     double dt) {
  InputBand out;
  out.input = name;
  const double variance = white_noise_variance(runs, false);
  out.noise_rms = std::sqrt(variance);
  std::size_t longest = 0;
  for (const auto& run : runs) longest = std::max(longest, run.size());
  std::size_t segment = 4096;
  while (segment > 256 && 4 * segment > longest) segment /= 2;
  const double nyquist = 0.5 / dt;
  if (!(variance > 0) || 2 * segment > longest) return out;
  const std::vector<double> psd = welch_psd(runs, dt, segment);
  const std::vector<double> frequency = psd_frequencies(dt, segment);
  const double floor = 2 * variance * dt;  // white noise's one-sided density
  std::size_t k = psd.size() - 1;
  while (k > 1 && !(psd[k] > InputBand::kFloorRatio * floor)) --k;
  out.edge = frequency[k];
  out.cutoff = std::max(1.5 * out.edge, frequency[std::min(k + 4, psd.size() - 1)]);
  out.filtered = out.cutoff < InputBand::kMaxCutoff * nyquist;
  return out;
}

void low_pass(std::vector<double>& x, double dt, const InputBand& band) {
  const std::size_t n = x.size();
  if (n < 2) return;
  const std::size_t pad = std::min<std::size_t>(n, 4096);
  std::size_t m = 1;
  while (m < n + 2 * pad) m *= 2;
  // The series mirrored at both ends (period 2n), so that its extension is continuous.
  std::vector<double> extended(m);
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t j = (i + 2 * n - pad % (2 * n)) % (2 * n);
    extended[i] = j < n ? x[j] : x[2 * n - 1 - j];
  }
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, extended);
  const double step = 1 / (static_cast<double>(m) * dt);
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    const double f = static_cast<double>(std::min(k, m - k)) * step;
    double gain = 1;
    if (f >= band.cutoff) {
      gain = 0;
    } else if (f > band.edge) {
      gain = 0.5 * (1 + std::cos(std::numbers::pi * (f - band.edge) / (band.cutoff - band.edge)));
    }
    spectrum[k] *= gain;
  }
  fft.inv(extended, spectrum);
  for (std::size_t i = 0; i < n; ++i) x[i] = extended[i + pad];
}

}  // namespace momentid
