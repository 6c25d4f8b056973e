#include "app/validate/residuals.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace momentid {

std::size_t CorrelationCheck::outside() const {
  return static_cast<std::size_t>(
      std::count_if(values.begin(), values.end(), [&](double v) { return std::abs(v) > band; }));
}

namespace {

// z of the two-sided 99% band.
constexpr double kBand99 = 2.5758293035489004;

// Series compared in several runs: segments of equal length in a and b.
struct Segments {
  std::vector<const double*> a, b;
  std::vector<std::size_t> length;
  void add(const std::vector<double>& x, const std::vector<double>& y) {
    a.push_back(x.data());
    b.push_back(y.data());
    length.push_back(y.size());
  }
};

// sum over segments and t of a[t] * b[t - lag], both inside the segment.
double lagged_sum(const Segments& s, int lag) {
  double sum = 0;
  for (std::size_t k = 0; k < s.length.size(); ++k) {
    const auto n = static_cast<long>(s.length[k]);
    const long from = std::max(0L, static_cast<long>(lag));
    const long to = std::min(n, n + lag);
    if (to <= from) continue;
    sum += Eigen::Map<const Eigen::VectorXd>(s.a[k] + from, to - from)
               .dot(Eigen::Map<const Eigen::VectorXd>(s.b[k] + from - lag, to - from));
  }
  return sum;
}

CorrelationCheck correlation(const Segments& s, int first, int last, double scale, double band,
                             const std::string& with) {
  CorrelationCheck c;
  c.with = with;
  c.first_lag = first;
  for (int lag = first; lag <= last; ++lag) c.values.push_back(lagged_sum(s, lag) / scale);
  c.band = band;
  return c;
}

// Input `column` of the record over the compared rows, run by run, less its mean there.
std::vector<std::vector<double>> centred_input(const Record& record, std::size_t column,
                                               const std::vector<std::size_t>& skip, double count) {
  std::vector<std::vector<double>> u(record.runs.size());
  double sum_u = 0;
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    const std::vector<double>& x = record.runs[r].columns[column];
    u[r].assign(x.begin() + static_cast<long>(skip[r]), x.end());
    for (double v : u[r]) sum_u += v;
  }
  for (std::vector<double>& run : u) {
    for (double& v : run) v -= sum_u / count;
  }
  return u;
}

// The cross-correlation of the error with an input, whose band is Bartlett's for independent
// series: var r_eu(k) = (1/N) sum_tau rho_e(tau) rho_u(tau). None for an input without spread.
std::optional<CorrelationCheck> cross_check(const Segments& errors,
                                            const std::vector<std::vector<double>>& u,
                                            const CorrelationCheck& autocorrelation, double e_power,
                                            double count, int lags, const std::string& name) {
  Segments input_self, cross;
  for (std::size_t r = 0; r < u.size(); ++r) {
    input_self.add(u[r], u[r]);
    cross.a.push_back(errors.a[r]);
    cross.b.push_back(u[r].data());
    cross.length.push_back(u[r].size());
  }
  const double u_power = lagged_sum(input_self, 0);
  if (!(u_power > 0)) return std::nullopt;
  double bartlett = 1;
  for (int lag = 1; lag <= lags; ++lag) {
    bartlett += 2 * autocorrelation.values[static_cast<std::size_t>(lag - 1)] *
                lagged_sum(input_self, lag) / u_power;
  }
  return correlation(cross, -lags, lags, std::sqrt(e_power * u_power),
                     kBand99 * std::sqrt(std::max(bartlett, 0.0) / count), name);
}

}  // namespace

void add_correlation_checks(const Model& model, const Record& record,
                            const std::vector<std::size_t>& skip,
                            std::vector<std::vector<double>> error, int lags, OutputFit& fit) {
  const double count = static_cast<double>(fit.samples);
  // Over the error with its mean removed.
  double sum_e = 0;
  for (const std::vector<double>& e : error) {
    for (double x : e) sum_e += x;
  }
  const double mean_e = sum_e / count;
  for (auto& e : error) {
    for (double& x : e) x -= mean_e;
  }
  Segments self;
  for (const std::vector<double>& e : error) self.add(e, e);
  const double e_power = lagged_sum(self, 0);
  if (!(e_power > 0)) return;
  fit.autocorrelation = correlation(self, 1, lags, e_power, kBand99 / std::sqrt(count), "");
  const std::size_t states = model.states().size();
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    const std::size_t column = static_cast<std::size_t>(record.column_of(states + i));
    const std::vector<std::vector<double>> u = centred_input(record, column, skip, count);
    if (auto check = cross_check(self, u, *fit.autocorrelation, e_power, count, lags,
                                 model.inputs()[i].name)) {
      fit.cross.push_back(std::move(*check));
    }
  }
}

}  // namespace momentid
