#include <cmath>
#include <map>

#include "momentid/estimate.hpp"

namespace momentid {

LaggedRows lagged_rows(const LaggedSystem& system, double dt, const std::vector<int>& channel) {
  LaggedRows out;
  std::map<Moment, std::size_t> index;
  const auto remap = [&](const Monomial& m) {
    Monomial out_m(m.size(), 0);
    for (std::size_t v = 0; v < m.size(); ++v) {
      if (m[v] != 0) out_m[static_cast<std::size_t>(channel[v])] += m[v];
    }
    return out_m;
  };
  // C^(k)[ψ;F](s) ~ sum_j w_j C[ψ;F](s + j) / dt^k.
  const auto entry = [&](const LagCombination& c, int s) {
    MomentRows::Entry e;
    for (const auto& [f, weight] : c) {
      const std::vector<double> w = stencil_weights(f.order);
      const int reach = kStencilReach[f.order];
      const double scale = weight.to_double() / std::pow(dt, f.order);
      const Monomial instrument = remap(f.instrument), function = remap(f.function);
      for (int j = -reach; j <= reach; ++j) {
        const double wj = w[static_cast<std::size_t>(j + reach)];
        if (wj == 0) continue;
        const Moment m = lagged_moment(instrument, function, s + j);
        const auto [it, inserted] = index.emplace(m, out.moments.size());
        if (inserted) out.moments.push_back(m);
        e.moments.emplace_back(it->second, scale * wj);
      }
    }
    return e;
  };
  for (int s = system.first_lag; s <= system.last_lag; ++s) {
    for (const LaggedEquation& eq : system.equations) {
      std::vector<MomentRows::Entry> a;
      for (const LagCombination& c : eq.coefficients) a.push_back(entry(c, s));
      out.rows.a.push_back(std::move(a));
      out.rows.b.push_back(entry(eq.rhs, s));
    }
  }
  return out;
}

}  // namespace momentid
