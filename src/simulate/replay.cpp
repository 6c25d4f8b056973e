// The response of a model to recorded inputs: interpolation between samples and integration.

#include <boost/math/special_functions/bessel.hpp>
#include <cmath>
#include <stdexcept>

#include "common/decimal.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/error.hpp"
#include "momentid/simulate.hpp"
#include "simulate/switching.hpp"

namespace momentid {
namespace {

constexpr int kSincHalfWidth = 24;
constexpr double kSincBeta = 14;

// The weights of samples n - 23 .. n + 24 for the value at t_n + fraction dt: a sinc through
// the offsets under a Kaiser window, scaled to sum to 1.
std::vector<double> sinc_weights(double fraction) {
  std::vector<double> w;
  double sum = 0;
  const double pi = 3.14159265358979323846;
  const double window_scale = boost::math::cyl_bessel_i(0, kSincBeta);
  for (int k = -kSincHalfWidth + 1; k <= kSincHalfWidth; ++k) {
    const double x = k - fraction;
    const double r = x / kSincHalfWidth;
    const double window =
        boost::math::cyl_bessel_i(0, kSincBeta * std::sqrt(1 - r * r)) / window_scale;
    w.push_back(std::sin(pi * x) / (pi * x) * window);
    sum += w.back();
  }
  for (double& v : w) v /= sum;
  return w;
}

}  // namespace

Interpolator::Interpolator(Interpolation method, std::vector<double> fractions)
    : method_(method), fractions_(std::move(fractions)) {
  if (method_ == Interpolation::kSinc) {
    for (double f : fractions_) sinc_.push_back(sinc_weights(f));
  }
}

double Interpolator::operator()(const std::vector<double>& u, std::size_t n, std::size_t k) const {
  const double f = fractions_[k];
  if (method_ == Interpolation::kHold) return u[n];
  const std::size_t rows = u.size();
  // Samples on each side of the interval: n + 1 up to its start, rows - 1 - n from its end.
  const std::size_t side = method_ == Interpolation::kLinear ? 1 : std::min(n + 1, rows - 1 - n);
  if (method_ == Interpolation::kSinc && side >= kSincHalfWidth) {
    const std::vector<double>& w = sinc_[k];
    const double* first = u.data() + n + 1 - kSincHalfWidth;
    double sum = 0;
    for (std::size_t j = 0; j < w.size(); ++j) sum += w[j] * first[j];
    return sum;
  }
  if (side >= 2) {
    // The cubic through samples n - 1 .. n + 2 (Lagrange).
    return -f * (f - 1) * (f - 2) / 6 * u[n - 1] + (f + 1) * (f - 1) * (f - 2) / 2 * u[n] -
           (f + 1) * f * (f - 2) / 2 * u[n + 1] + (f + 1) * f * (f - 1) / 6 * u[n + 2];
  }
  if (rows >= 3 && method_ != Interpolation::kLinear) {
    // The quadratic through three samples, the third on the side that has one.
    if (n == 0) {
      return (f - 1) * (f - 2) / 2 * u[0] - f * (f - 2) * u[1] + f * (f - 1) / 2 * u[2];
    }
    return f * (f - 1) / 2 * u[n - 1] + (1 - f * f) * u[n] + (f + 1) * f / 2 * u[n + 1];
  }
  return (1 - f) * u[n] + f * u[n + 1];
}

RecordSimulator::RecordSimulator(const Model& model, const ParameterValues& parameters,
                                 std::vector<Interpolation> methods, double dt, int substeps)
    // Each GiNaC value made here is made and destroyed under the lock.
    : model_(model),
      parameter_text_([&] {
        const AlgebraLock lock;
        return parameter_list(model, parameter_vector(model, parameters));
      }()),
      f_([&] {
        const AlgebraLock lock;
        return CompiledModel(model, parameter_vector(model, parameters));
      }()),
      methods_(std::move(methods)),
      dt_(dt),
      substeps_(substeps) {
  if (methods_.size() != model.inputs().size()) {
    throw std::invalid_argument("RecordSimulator: one interpolation method per input needed");
  }
  if (substeps < 1 || substeps > kMaxSubsteps) {
    throw std::invalid_argument("RecordSimulator: substeps out of range");
  }
  // Fractions k / (2 substeps), k = 1 .. 2 substeps - 1: the substeps' middles and inner ends.
  std::vector<double> fractions;
  for (int k = 1; k < 2 * substeps; ++k) fractions.push_back(k / (2.0 * substeps));
  for (Interpolation method : methods_) within_.emplace_back(method, fractions);
}

std::vector<std::vector<double>> RecordSimulator::derivatives(
    const std::vector<std::vector<double>>& states,
    const std::vector<std::vector<double>>& inputs) const {
  const std::vector<MeasuredDerivative>& measured = model_.measured_derivatives();
  const std::size_t rows = states.empty() ? 0 : states.front().size();
  std::vector<std::vector<double>> out(measured.size(), std::vector<double>(rows, NAN));
  std::vector<double> y(states.size()), u(inputs.size()), rates(states.size());
  for (std::size_t n = 0; n < rows && !measured.empty(); ++n) {
    for (std::size_t j = 0; j < y.size(); ++j) y[j] = states[j][n];
    for (std::size_t i = 0; i < u.size(); ++i) u[i] = inputs[i][n];
    if (!f_.derivative(y.data(), u.data(), rates.data())) continue;
    for (std::size_t i = 0; i < measured.size(); ++i) {
      out[i][n] = rates[static_cast<std::size_t>(measured[i].state)];
    }
  }
  return out;
}

std::vector<std::vector<double>> RecordSimulator::run(
    const std::vector<std::vector<double>>& inputs, const std::vector<double>& initial,
    double start, std::size_t run_number, std::size_t rows) const {
  const std::size_t n = static_cast<std::size_t>(f_.states());
  const std::size_t m = static_cast<std::size_t>(f_.inputs());
  if (inputs.size() != m || initial.size() != n) {
    throw std::invalid_argument("RecordSimulator::run: one column per input, one value per state");
  }
  for (const auto& column : inputs) {
    if (column.size() < rows) {
      throw std::invalid_argument("RecordSimulator::run: input columns shorter than the run");
    }
  }
  SwitchingStep step(f_);
  std::vector<std::vector<double>> states(n, std::vector<double>(rows));
  std::vector<double> y = initial, u0(m), um(m), u1(m);
  const double h = dt_ / substeps_;
  const auto fail = [&](const std::string& what, std::size_t row) {
    throw Error("the simulation " + what +
                " at t = " + shortest_decimal(start + static_cast<double>(row) * dt_) + " in run " +
                std::to_string(run_number) + " with " + parameter_text_ +
                ": the model is unstable for these values, or the sample interval is too "
                "large for it");
  };
  // Input i at fraction k / (2 substeps) of interval s.
  const auto input = [&](std::size_t i, std::size_t s, int k) {
    if (k == 0 || methods_[i] == Interpolation::kHold) return inputs[i][s];
    if (k == 2 * substeps_) return inputs[i][s + 1];
    return within_[i](inputs[i], s, static_cast<std::size_t>(k - 1));
  };
  if (rows > 0) {
    for (std::size_t i = 0; i < m; ++i) u0[i] = input(i, 0, 0);
    if (!step.start(y.data(), u0.data())) {
      fail("met a point where the derivatives cannot be solved for", 0);
    }
  }
  for (std::size_t s = 0; s < rows; ++s) {
    for (std::size_t j = 0; j < n; ++j) states[j][s] = y[j];
    if (s + 1 == rows) break;
    for (int sub = 0; sub < substeps_; ++sub) {
      for (std::size_t i = 0; i < m; ++i) {
        u0[i] = input(i, s, 2 * sub);
        um[i] = input(i, s, 2 * sub + 1);
        u1[i] = input(i, s, 2 * sub + 2);
      }
      if (!step(y.data(), u0.data(), um.data(), u1.data(), h)) {
        fail("met a point where the derivatives cannot be solved for", s);
      }
      const int blown = step.blown_up(y.data());
      if (blown >= 0) {
        fail("blew up: state '" + model_.states()[static_cast<std::size_t>(blown)].name +
                 "' reached " + shortest_decimal(y[static_cast<std::size_t>(blown)]),
             s + 1);
      }
    }
  }
  return states;
}

}  // namespace momentid
