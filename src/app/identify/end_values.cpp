// The record's ends: the zero-lag equations take the stationarity identities E[(g)'] = 0, which
// a finite record meets only up to (g(end) - g(start)) / T (docs/uncertainty.md, "End values").

#include "app/identify/end_values.hpp"

namespace momentid {

void increments_to_rates(const std::vector<Monomial>& moments, std::optional<double> interval,
                         MomentEstimates& estimates) {
  for (std::size_t k = 0; k < moments.size(); ++k) {
    if (!moments[k].rate()) continue;
    const double scale = interval ? 1 / *interval : 0.0;
    estimates.mean[k] *= scale;
    for (std::vector<double>& batch : estimates.batch_means) batch[k] *= scale;
  }
}

std::vector<Monomial> rate_monomials(const std::vector<Monomial>& moments) {
  std::vector<Monomial> out;
  for (const Monomial& m : moments) {
    if (m.rate()) out.push_back(m.without_rate());
  }
  return out;
}

std::vector<std::vector<double>> rate_covariance(const std::vector<Monomial>& g,
                                                 const std::vector<double>& means, std::size_t runs,
                                                 double duration) {
  // with_products(g): the g, then g_i g_j for i <= j.
  std::vector<std::vector<double>> out(g.size(), std::vector<double>(g.size()));
  for (std::size_t i = 0, next = g.size(); i < g.size(); ++i) {
    for (std::size_t j = i; j < g.size(); ++j, ++next) {
      const double c = means.at(next) - means.at(i) * means.at(j);
      out[i][j] = out[j][i] = 2 * static_cast<double>(runs) * c / (duration * duration);
    }
  }
  return out;
}

}  // namespace momentid
