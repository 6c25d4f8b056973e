// The response of a model to recorded inputs: interpolation between samples and integration.

#include <boost/math/special_functions/bessel.hpp>
#include <cmath>
#include <stdexcept>

#include "common/decimal.hpp"
#include "momentid/error.hpp"
#include "momentid/simulate.hpp"
#include "simulate/step.hpp"

namespace momentid {
namespace {

constexpr int kSincHalfWidth = 24;
constexpr double kSincBeta = 14;

// The weights of samples n - 23 .. n + 24 for the value at the middle of interval n: a sinc
// through the half-sample offsets under a Kaiser window, scaled to sum to 1.
std::vector<double> sinc_weights() {
  std::vector<double> w;
  double sum = 0;
  const double pi = 3.14159265358979323846;
  const double window_scale = boost::math::cyl_bessel_i(0, kSincBeta);
  for (int k = -kSincHalfWidth + 1; k <= kSincHalfWidth; ++k) {
    const double x = k - 0.5;
    const double r = x / kSincHalfWidth;
    const double window = boost::math::cyl_bessel_i(0, kSincBeta * std::sqrt(1 - r * r)) /
                          window_scale;
    w.push_back(std::sin(pi * x) / (pi * x) * window);
    sum += w.back();
  }
  for (double& v : w) v /= sum;
  return w;
}

}  // namespace

std::string interpolation_name(Interpolation method) {
  switch (method) {
    case Interpolation::kHold:
      return "zoh";
    case Interpolation::kLinear:
      return "foh";
    case Interpolation::kCubic:
      return "cubic";
    case Interpolation::kSinc:
      return "sinc";
  }
  return "";
}

Interpolation parse_interpolation(const std::string& text, const std::string& option) {
  for (Interpolation m : {Interpolation::kHold, Interpolation::kLinear, Interpolation::kCubic,
                          Interpolation::kSinc}) {
    if (text == interpolation_name(m)) return m;
  }
  throw UsageError(option + ": expected zoh, foh, cubic or sinc, found '" + text + "'");
}

std::vector<double> interval_midpoints(const std::vector<double>& u, Interpolation method) {
  const std::size_t rows = u.size();
  if (rows < 2) return {};
  std::vector<double> mid(rows - 1);
  static const std::vector<double> sinc = sinc_weights();
  const auto reach = [&](std::size_t n) { return std::min(n + 1, rows - 1 - n); };
  for (std::size_t n = 0; n + 1 < rows; ++n) {
    if (method == Interpolation::kHold) {
      mid[n] = u[n];
      continue;
    }
    // Samples available on each side of the interval: n + 1 before its end, rows - 1 - n after
    // its start.
    const std::size_t side = method == Interpolation::kLinear ? 1 : reach(n);
    if (method == Interpolation::kSinc && side >= kSincHalfWidth) {
      double sum = 0;
      const double* first = u.data() + n + 1 - kSincHalfWidth;
      for (std::size_t k = 0; k < sinc.size(); ++k) sum += sinc[k] * first[k];
      mid[n] = sum;
    } else if (side >= 2) {
      mid[n] = (9 * (u[n] + u[n + 1]) - (u[n - 1] + u[n + 2])) / 16;
    } else if (rows >= 3 && method != Interpolation::kLinear) {
      // The quadratic through three samples, the third on the side that has one.
      mid[n] = n == 0 ? (3 * u[0] + 6 * u[1] - u[2]) / 8
                      : (-u[n - 1] + 6 * u[n] + 3 * u[n + 1]) / 8;
    } else {
      mid[n] = (u[n] + u[n + 1]) / 2;
    }
  }
  return mid;
}

RecordSimulator::RecordSimulator(const Model& model, std::vector<GiNaC::numeric> parameters,
                                 std::vector<Interpolation> methods, double dt)
    : model_(model),
      parameters_(std::move(parameters)),
      f_(model, parameters_),
      methods_(std::move(methods)),
      dt_(dt) {
  if (methods_.size() != model.inputs().size()) {
    throw std::invalid_argument("RecordSimulator: one interpolation method per input needed");
  }
}

std::vector<std::vector<double>> RecordSimulator::run(const std::vector<std::vector<double>>& inputs,
                                                      const std::vector<double>& initial,
                                                      double start, std::size_t run_number,
                                                      std::size_t rows) const {
  const std::size_t n = static_cast<std::size_t>(f_.states());
  const std::size_t m = static_cast<std::size_t>(f_.inputs());
  if (inputs.size() != m || initial.size() != n) {
    throw std::invalid_argument("RecordSimulator::run: one column per input, one value per state");
  }
  const std::size_t length = m == 0 ? rows : inputs[0].size();
  for (const auto& column : inputs) {
    if (column.size() != length) {
      throw std::invalid_argument("RecordSimulator::run: input columns of different lengths");
    }
  }
  if (rows == 0 || rows > length) rows = length;
  std::vector<std::vector<double>> middles(m);
  for (std::size_t i = 0; i < m; ++i) {
    if (methods_[i] != Interpolation::kHold) {
      middles[i] = interval_midpoints(
          std::vector<double>(inputs[i].begin(), inputs[i].begin() + static_cast<long>(rows)),
          methods_[i]);
    }
  }
  RungeKuttaStep step(f_);
  std::vector<std::vector<double>> states(n, std::vector<double>(rows));
  std::vector<double> y = initial, u0(m), um(m), u1(m);
  for (std::size_t s = 0; s < rows; ++s) {
    for (std::size_t j = 0; j < n; ++j) states[j][s] = y[j];
    if (s + 1 == rows) break;
    for (std::size_t i = 0; i < m; ++i) {
      const bool held = methods_[i] == Interpolation::kHold;
      u0[i] = inputs[i][s];
      um[i] = held ? u0[i] : middles[i][s];
      u1[i] = held ? u0[i] : inputs[i][s + 1];
    }
    const auto fail = [&](const std::string& what, std::size_t row) {
      throw Error("the simulation " + what + " at t = " +
                  shortest_decimal(start + static_cast<double>(row) * dt_) + " in run " +
                  std::to_string(run_number) + " with " + parameter_list(model_, parameters_) +
                  ": the model is unstable for these values, or the sample interval is too "
                  "large for it");
    };
    if (!step(y.data(), u0.data(), um.data(), u1.data(), dt_)) {
      fail("met a point where the derivatives cannot be solved for", s);
    }
    const int blown = step.blown_up(y.data());
    if (blown >= 0) {
      fail("blew up: state '" + model_.states()[static_cast<std::size_t>(blown)].name +
               "' reached " + shortest_decimal(y[static_cast<std::size_t>(blown)]),
           s + 1);
    }
  }
  return states;
}

}  // namespace momentid
