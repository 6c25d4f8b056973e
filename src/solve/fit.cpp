#include <limits>

#include "momentid/estimate.hpp"

namespace momentid {

std::vector<std::vector<double>> Fit::covariance() const {
  const std::size_t n = parameters.size();
  std::vector<std::vector<double>> out(
      n, std::vector<double>(n, std::numeric_limits<double>::quiet_NaN()));
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      const ParameterEstimate &a = parameters[i], &b = parameters[j];
      if (a.fixed || b.fixed) {
        out[i][j] = 0;
      } else if (i == j) {
        out[i][j] = a.std_error * a.std_error;
      } else if (!correlation.empty()) {
        out[i][j] = correlation[i][j] * a.std_error * b.std_error;
      }
    }
  }
  return out;
}

}  // namespace momentid
