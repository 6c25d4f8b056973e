// The lagged moment equations as numbers: each equation summed over lags against each test
// function of the lag, the lag derivatives moved onto the test function, and powers of noisy
// channels replaced by their Hermite polynomials in the noise variance (not where a channel is
// inside an abs or sign factor of the same moment).

#include <algorithm>
#include <cmath>
#include <map>

#include "momentid/estimate.hpp"
#include "solve/rows.hpp"

namespace momentid {

LaggedRows lagged_rows(const LaggedSystem& system, double dt, const std::vector<int>& channel,
                       const std::vector<double>& noise, int stencil) {
  LaggedRows out;
  std::map<Moment, std::size_t> index;
  const std::vector<std::vector<std::size_t>> from = computed_from(*system.model, channel);
  const auto remap = [&](const Monomial& m) {
    Monomial out_m(m.size(), 0);
    for (std::size_t v = 0; v < m.size(); ++v) {
      if (m[v] != 0) out_m[static_cast<std::size_t>(channel[v])] += m[v];
    }
    return out_m;
  };
  // Σ_s φ(s) C^(k)[ψ;F](s) with C^(k)(s) ~ Σ_j w_j C(s + j) / dt^k is Σ_s C(s) Σ_j w_j φ(s − j)
  // / dt^k: the stencil applied to F at each instrument time, as the accumulator reads the
  // moments, so that the sums are the equations at the samples, weighted. (A held input needs
  // nothing more: the accumulator's moments of it already carry, at each sample, the mean input
  // that the five-point stencil of a state it drives sees.) Each C with ψ and F noise-corrected.
  // Every lag of the window is listed, zero weights too: the moments enter in the same order
  // whatever the noise variances and the stencil, so that the list can be made before the pass.
  const auto entry = [&](const LagCombination& c, const LagTestFunction& phi) {
    MomentRows::Entry e;
    for (const auto& [f, weight] : c) {
      const std::vector<double> w = stencil_weights(f.order, stencil);
      const int reach = stencil_reach(f.order, stencil);
      const double scale = weight.to_double() / std::pow(dt, f.order);
      const auto instruments = noise_corrected(remap(f.instrument), noise);
      // The instrument, at an earlier time, carries noise independent of the function's.
      const Monomial read = remap(f.function);
      const auto functions = noise_corrected(read, correctable_noise(read, noise, from));
      for (int s = system.first_lag; s <= system.last_lag; ++s) {
        double ws = 0;
        for (int j = -reach; j <= reach; ++j) {
          ws += w[static_cast<std::size_t>(j + reach)] * phi(s - j);
        }
        for (const auto& [instrument, wi] : instruments) {
          for (const auto& [function, wf] : functions) {
            const bool constant =
                std::all_of(instrument.begin(), instrument.end(), [](int p) { return p == 0; }) &&
                std::all_of(function.begin(), function.end(), [](int p) { return p == 0; });
            if (constant) {
              e.constant += scale * ws * wi * wf;
              continue;
            }
            const Moment m = lagged_moment(instrument, function, s);
            const auto [it, inserted] = index.emplace(m, out.moments.size());
            if (inserted) out.moments.push_back(m);
            e.moments.emplace_back(it->second, scale * ws * wi * wf);
          }
        }
      }
    }
    return e;
  };
  for (const LagTestFunction& phi : system.test_functions) {
    for (const LaggedEquation& eq : system.equations) {
      std::vector<MomentRows::Entry> a;
      for (const LagCombination& c : eq.coefficients) a.push_back(entry(c, phi));
      out.rows.a.push_back(std::move(a));
      out.rows.b.push_back(entry(eq.rhs, phi));
    }
  }
  return out;
}

}  // namespace momentid
