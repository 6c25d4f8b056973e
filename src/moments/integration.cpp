#include "moments/integration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

namespace momentid {
namespace {

// The taps end where every response has fallen below this fraction of its largest.
constexpr double kTail = 1e-10;
// At most this reach each side (0.04 Hz at 2048 Hz), which keeps the design grid to 2^22 points.
constexpr std::size_t kMaxReach = std::size_t{1} << 19;

std::size_t power_of_two_from(std::size_t n) {
  std::size_t out = 1;
  while (out < n) out *= 2;
  return out;
}

// The frequency response of a channel integrated `integrals` times at w (rad/s): the
// Butterworth magnitude 1/sqrt(1 + (wc/w)^8), divided by (i w)^integrals.
std::complex<double> response(double w, double wc, int integrals) {
  if (w <= 0) return 0;
  const double magnitude = 1 / std::sqrt(1 + std::pow(wc / w, 8));
  return magnitude / std::pow(std::complex<double>(0, w), integrals);
}

}  // namespace

IntegrationFilter::IntegrationFilter(const DataOptions::Integration& integration)
    : channels_(integration.integrals.size()) {
  const double dt = integration.dt, corner = integration.corner;
  if (!(corner > 0 && dt > 0 && corner * dt < 0.5)) {
    throw std::invalid_argument("IntegrationFilter: the corner must lie between 0 and Nyquist");
  }
  for (const int integrals : integration.integrals) {
    if (integrals < 0 || integrals > 2) {
      throw std::invalid_argument("IntegrationFilter: 0, 1 or 2 integrals per channel");
    }
  }
  // The responses' singularities nearest the real axis lie at wc e^(i pi/8): they fall off as
  // exp(-wc sin(pi/8) |t|), and a grid four times that long keeps their wrap-around below the
  // tail.
  const double wc = 2 * std::numbers::pi * corner;
  const double reach = std::log(1 / kTail) / (wc * std::sin(std::numbers::pi / 8) * dt);
  if (!(reach < static_cast<double>(kMaxReach))) {
    throw std::invalid_argument("IntegrationFilter: the corner is too low for the filter's length");
  }
  const std::size_t grid =
      power_of_two_from(std::max<std::size_t>(4096, 8 * static_cast<std::size_t>(reach)));
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  // The zero-phase impulse response of each kind of channel, centred on sample 0 of the grid.
  std::vector<std::vector<double>> centred(3);
  std::size_t half = 0;
  for (int r = 0; r < 3; ++r) {
    if (std::find(integration.integrals.begin(), integration.integrals.end(), r) ==
        integration.integrals.end()) {
      continue;
    }
    std::vector<std::complex<double>> spectrum(grid / 2 + 1);
    for (std::size_t k = 0; k + 1 < spectrum.size(); ++k) {
      spectrum[k] = response(
          2 * std::numbers::pi * static_cast<double>(k) / (static_cast<double>(grid) * dt), wc, r);
    }
    // Nyquist holds a real value for a real response: the odd one's is left at 0.
    spectrum.back() = r == 1 ? 0.0 : response(std::numbers::pi / dt, wc, r).real();
    fft.inv(centred[static_cast<std::size_t>(r)], spectrum, static_cast<long>(grid));
    const std::vector<double>& h = centred[static_cast<std::size_t>(r)];
    double largest = 0;
    for (double x : h) largest = std::max(largest, std::abs(x));
    for (std::size_t n = 1; n < grid / 2; ++n) {
      if (std::abs(h[n]) > kTail * largest || std::abs(h[grid - n]) > kTail * largest) half = n;
    }
  }
  taps_ = 2 * half + 1;
  size_ = power_of_two_from(2 * taps_);
  for (const int integrals : integration.integrals) {
    const std::vector<double>& h = centred[static_cast<std::size_t>(integrals)];
    std::vector<double> taps(taps_);
    for (std::size_t j = 0; j < taps_; ++j) taps[j] = h[(j + grid - half) % grid];
    std::vector<double> padded(size_, 0.0);
    std::copy(taps.begin(), taps.end(), padded.begin());
    std::vector<std::complex<double>> spectrum;
    fft.fwd(spectrum, padded);
    taps_of_.push_back(std::move(taps));
    spectrum_.push_back(std::move(spectrum));
  }
}

double IntegrationFilter::noise_gain(std::size_t c) const {
  double sum = 0;
  for (double h : taps_of_.at(c)) sum += h * h;
  return sum;
}

void IntegrationFilter::start_run() {
  input_.clear();
  seen_ = 0;
}

void IntegrationFilter::push(const double* rows, std::size_t count, std::vector<double>& out) {
  input_.insert(input_.end(), rows, rows + count * channels_);
  seen_ += count;
  const std::size_t block = size_ - taps_ + 1;
  while (input_.size() / channels_ >= taps_ - 1 + block) convolve(block, out);
}

void IntegrationFilter::flush(std::vector<double>& out) {
  const std::size_t held = input_.size() / std::max<std::size_t>(channels_, 1);
  if (held > taps_ - 1) convolve(held - (taps_ - 1), out);
  input_.clear();
}

// Overlap-save: the taps_ - 1 rows before and `fresh` rows give `fresh` rows of output.
void IntegrationFilter::convolve(std::size_t fresh, std::vector<double>& out) {
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  const std::size_t rows = taps_ - 1 + fresh, first = out.size();
  out.resize(first + fresh * channels_);
  std::vector<double> segment(size_), result;
  std::vector<std::complex<double>> spectrum;
  for (std::size_t c = 0; c < channels_; ++c) {
    std::fill(segment.begin(), segment.end(), 0.0);
    for (std::size_t i = 0; i < rows; ++i) segment[i] = input_[i * channels_ + c];
    fft.fwd(spectrum, segment);
    for (std::size_t k = 0; k < spectrum.size(); ++k) spectrum[k] *= spectrum_[c][k];
    fft.inv(result, spectrum, static_cast<long>(size_));
    for (std::size_t i = 0; i < fresh; ++i) out[first + i * channels_ + c] = result[taps_ - 1 + i];
  }
  input_.erase(input_.begin(), input_.begin() + static_cast<long>(fresh * channels_));
}

}  // namespace momentid
