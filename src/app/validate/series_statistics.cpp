#include "app/validate/series_statistics.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <unsupported/Eigen/FFT>
#include <utility>

#include "momentid/data_pass.hpp"

namespace momentid {

std::vector<double> welch_psd(const std::vector<std::vector<double>>& runs, double dt,
                              std::size_t segment) {
  std::vector<double> window(segment);
  double window_power = 0;
  for (std::size_t i = 0; i < segment; ++i) {
    const double s =
        std::sin(std::numbers::pi * static_cast<double>(i) / static_cast<double>(segment));
    window[i] = s * s;  // the periodic Hann window, which half-overlapping segments sum flat
    window_power += window[i] * window[i];
  }
  const std::size_t bins = segment / 2 + 1;
  std::vector<double> out(bins, 0.0), tapered(segment);
  std::vector<std::complex<double>> spectrum;
  Eigen::FFT<double> fft;
  std::size_t segments = 0;
  for (const std::vector<double>& run : runs) {
    for (std::size_t start = 0; start + segment <= run.size(); start += segment / 2) {
      double mean = 0;
      for (std::size_t i = 0; i < segment; ++i) mean += run[start + i];
      mean /= static_cast<double>(segment);
      for (std::size_t i = 0; i < segment; ++i) tapered[i] = window[i] * (run[start + i] - mean);
      fft.fwd(spectrum, tapered);
      for (std::size_t k = 0; k < bins; ++k) out[k] += std::norm(spectrum[k]);
      ++segments;
    }
  }
  if (segments == 0) return out;
  // One-sided: every frequency but 0 and Nyquist holds its negative twin's power too.
  for (std::size_t k = 0; k < bins; ++k) {
    const double side = k == 0 || 2 * k == segment ? 1.0 : 2.0;
    out[k] *= side * dt / (window_power * static_cast<double>(segments));
  }
  return out;
}

std::vector<double> psd_frequencies(double dt, std::size_t segment) {
  std::vector<double> out(segment / 2 + 1);
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k] = static_cast<double>(k) / (static_cast<double>(segment) * dt);
  }
  return out;
}

std::vector<double> quantiles(const std::vector<std::vector<double>>& runs,
                              const std::vector<double>& probabilities) {
  std::vector<double> values;
  for (const std::vector<double>& run : runs) values.insert(values.end(), run.begin(), run.end());
  std::vector<double> out;
  if (values.empty()) return std::vector<double>(probabilities.size(), NAN);
  std::sort(values.begin(), values.end());
  for (double p : probabilities) {
    const double at = p * static_cast<double>(values.size() - 1);
    const auto low = static_cast<std::size_t>(std::floor(at));
    const std::size_t high = std::min(low + 1, values.size() - 1);
    const double weight = at - static_cast<double>(low);
    out.push_back((1 - weight) * values[low] + weight * values[high]);
  }
  return out;
}

std::vector<double> upcrossing_rates(const std::vector<std::vector<double>>& runs, double dt,
                                     const std::vector<double>& levels, double hysteresis) {
  std::vector<double> out;
  std::size_t rows = 0;
  for (const std::vector<double>& run : runs) rows += run.size();
  for (double level : levels) {
    std::size_t crossings = 0;
    for (const std::vector<double>& run : runs) {
      bool below = false;  // armed by a value below level - hysteresis
      for (double x : run) {
        if (x < level - hysteresis) {
          below = true;
        } else if (below && x > level + hysteresis) {
          ++crossings;
          below = false;
        }
      }
    }
    out.push_back(rows > 0 ? static_cast<double>(crossings) / (static_cast<double>(rows) * dt)
                           : NAN);
  }
  return out;
}

std::pair<double, double> mean_and_spread(const std::vector<std::vector<double>>& runs) {
  double sum = 0, squares = 0, count = 0;
  for (const std::vector<double>& run : runs) {
    for (double x : run) sum += x;
    count += static_cast<double>(run.size());
  }
  const double mean = sum / count;
  for (const std::vector<double>& run : runs) {
    for (double x : run) squares += (x - mean) * (x - mean);
  }
  return {mean, std::sqrt(squares / count)};
}

double white_noise_variance(const std::vector<std::vector<double>>& runs, bool held) {
  const auto [mean, spread] = mean_and_spread(runs);
  if (!(spread > 0)) return 0;
  if (!held) {
    double squares = 0, rows = 0;
    for (const std::vector<double>& run : runs) {
      for (std::size_t n = kNoiseDifference; n < run.size(); ++n) {
        const double d = sixth_difference(run.data() + n);
        squares += d * d;
        ++rows;
      }
    }
    return rows > 0 ? squares / rows / kSixthDifferenceGain : 0.0;
  }
  std::vector<double> rho(4);
  for (std::size_t lag = 1; lag <= 4; ++lag) {
    double products = 0, pairs = 0;
    for (const std::vector<double>& run : runs) {
      for (std::size_t n = lag; n < run.size(); ++n) {
        products += (run[n] - mean) * (run[n - lag] - mean);
      }
      pairs += run.size() > lag ? static_cast<double>(run.size() - lag) : 0.0;
    }
    rho[lag - 1] = products / pairs / (spread * spread);
  }
  return std::max(0.0, spread * spread * (1 - held_lag_zero(rho)));
}

double prediction_bound(const std::vector<double>& values, double t) {
  const auto k = static_cast<double>(values.size());
  const bool positive = std::all_of(values.begin(), values.end(), [](double v) { return v > 0; });
  double mean = 0, squares = 0;
  for (double v : values) mean += (positive ? std::log(v) : v) / k;
  for (double v : values) squares += std::pow((positive ? std::log(v) : v) - mean, 2);
  const double bound = mean + t * std::sqrt(squares / (k - 1)) * std::sqrt(1 + 1 / k);
  return positive ? std::exp(bound) : bound;
}

}  // namespace momentid
