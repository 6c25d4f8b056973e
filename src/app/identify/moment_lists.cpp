// The lists of moments a zero-lag pass reads: the increments for the rates of change, the
// moments added for the refinements, and the system's own first.

#include "app/identify/moment_lists.hpp"

#include <algorithm>
#include <set>

namespace momentid {

std::vector<Moment> pass_moments_of(const std::vector<Monomial>& moments) {
  std::vector<Moment> out;
  for (const Monomial& m : moments) {
    out.push_back(m.rate() ? Moment::increment_of(m.without_rate()) : Moment::from_monomial(m));
  }
  return out;
}

std::vector<Monomial> without_rates(std::vector<Monomial> moments) {
  std::erase_if(moments, [](const Monomial& m) { return m.rate(); });
  return moments;
}

std::vector<Monomial> with_products(const std::vector<Monomial>& g) {
  std::vector<Monomial> out = g;
  for (std::size_t i = 0; i < g.size(); ++i) {
    for (std::size_t j = i; j < g.size(); ++j) {
      Monomial product = g[i];
      for (std::size_t v = 0; v < product.size(); ++v) product[v] += g[j][v];
      out.push_back(std::move(product));
    }
  }
  return out;
}

std::map<Moment, std::size_t> moment_index(const std::vector<Moment>& moments) {
  std::map<Moment, std::size_t> out;
  for (std::size_t k = 0; k < moments.size(); ++k) out.emplace(moments[k], k);
  return out;
}

MomentEstimates moments_at(const MomentEstimates& all, const std::vector<std::size_t>& index) {
  MomentEstimates out;
  out.batch_intervals = all.batch_intervals;
  out.intervals = all.intervals;
  for (std::size_t k : index) out.mean.push_back(all.mean[k]);
  for (const std::vector<double>& batch : all.batch_means) {
    std::vector<double>& to = out.batch_means.emplace_back();
    for (std::size_t k : index) to.push_back(batch[k]);
  }
  return out;
}

MomentEstimates first_moments(const MomentEstimates& all, std::size_t count) {
  MomentEstimates out = all;
  out.mean.resize(count);
  for (std::vector<double>& batch : out.batch_means) batch.resize(count);
  return out;
}

std::vector<Monomial> not_among(const std::vector<Monomial>& moments,
                                const std::vector<Monomial>& more) {
  std::set<Monomial> known(moments.begin(), moments.end());
  std::vector<Monomial> out;
  for (const Monomial& m : more) {
    const bool constant = std::all_of(m.begin(), m.end(), [](int e) { return e == 0; });
    if (!constant && known.insert(m).second) out.push_back(m);
  }
  return out;
}

}  // namespace momentid
