#include "moments/integration.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

namespace momentid {
namespace {

// The transient of a start from rest falls below this fraction before the rows are used.
constexpr double kSettled = 1e-9;

// The larger modulus of the roots of z^2 + a1 z + a2.
double pole_radius(double a1, double a2) {
  const std::complex<double> root = std::sqrt(std::complex<double>(a1 * a1 - 4 * a2, 0));
  return std::max(std::abs((-a1 + root) / 2.0), std::abs((-a1 - root) / 2.0));
}

}  // namespace

IntegrationFilter::IntegrationFilter(const DataOptions::Integration& integration) {
  if (!(integration.corner > 0 && integration.dt > 0 &&
        integration.corner * integration.dt < 0.5)) {
    throw std::invalid_argument("IntegrationFilter: the corner must lie between 0 and Nyquist");
  }
  // The bilinear transform of the Butterworth high-pass s^4/B(s), whose two sections have the
  // quality factors 1/(2 cos(pi/8)) and 1/(2 cos(3 pi/8)); an integral replaces a factor
  // (1 - 1/z) of a section's numerator by the trapezoidal rule's dt/2 (1 + 1/z), the bilinear
  // transform of 1/s, so that the formed channel is the same filter's output of the integral.
  const double k = std::tan(std::numbers::pi * integration.corner * integration.dt);
  const double half = integration.dt / 2;
  std::array<Section, 2> high_pass;
  double radius = 0;
  for (int i = 0; i < 2; ++i) {
    const double q = 1 / (2 * std::cos(std::numbers::pi * (2 * i + 1) / 8));
    const double d = 1 + k / q + k * k;
    Section& s = high_pass[static_cast<std::size_t>(i)];
    s = {1 / d, -2 / d, 1 / d, 2 * (k * k - 1) / d, (1 - k / q + k * k) / d};
    radius = std::max(radius, pole_radius(s.a1, s.a2));
  }
  warm_up_ = static_cast<std::size_t>(std::ceil(std::log(kSettled) / std::log(radius))) + 2;
  for (const int integrals : integration.integrals) {
    if (integrals < 0 || integrals > 2) {
      throw std::invalid_argument("IntegrationFilter: 0, 1 or 2 integrals per channel");
    }
    Channel c;
    c.sections = high_pass;
    Section& first = c.sections[0];
    const double d = first.b0;  // 1/d of the section
    if (integrals == 1) first = {half * d, 0, -half * d, first.a1, first.a2};
    if (integrals == 2)
      first = {half * half * d, 2 * half * half * d, half * half * d, first.a1, first.a2};
    // The trapezoidal rule's gain falls as (x / tan x)^r at x = omega dt / 2; 1 - c*delta^2,
    // a central second difference, gives it back to O(x^4) (1/12 per integral).
    c.correction = integrals / 12.0;
    channels_.push_back(c);
  }
}

double IntegrationFilter::noise_gain(std::size_t c) const {
  Channel impulse = channels_.at(c);
  impulse.state = {};
  impulse.past = {};
  double sum = 0;
  for (std::size_t n = 0; n < warm_up_; ++n) {
    const double h = step(impulse, n == 0 ? 1.0 : 0.0);
    sum += h * h;
  }
  return sum;
}

void IntegrationFilter::start_run() {
  seen_ = 0;
  for (Channel& c : channels_) {
    c.state = {};
    c.past = {};
  }
}

double IntegrationFilter::step(Channel& c, double x) const {
  for (std::size_t i = 0; i < 2; ++i) {
    const Section& s = c.sections[i];
    double* z = &c.state[2 * i];
    const double y = s.b0 * x + z[0];
    z[0] = s.b1 * x - s.a1 * y + z[1];
    z[1] = s.b2 * x - s.a2 * y;
    x = y;
  }
  // The output of the row before, corrected with the rows on either side.
  const double out = c.past[0] - c.correction * (x - 2 * c.past[0] + c.past[1]);
  c.past[1] = c.past[0];
  c.past[0] = x;
  return out;
}

std::size_t IntegrationFilter::apply(double* values, std::size_t count) {
  const std::size_t width = channels_.size();
  std::size_t kept = 0;
  for (std::size_t r = 0; r < count; ++r, ++seen_) {
    double* row = values + r * width;
    for (std::size_t c = 0; c < width; ++c) row[c] = step(channels_[c], row[c]);
    if (seen_ < warm_up_) continue;
    if (kept != r) std::copy(row, row + width, values + kept * width);
    ++kept;
  }
  return kept;
}

}  // namespace momentid
