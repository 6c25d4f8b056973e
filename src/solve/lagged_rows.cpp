// The lagged moment equations as numbers: each equation summed over lags against each test
// function of the lag, the lag derivatives moved onto the test function, and powers of noisy
// channels replaced by their Hermite polynomials in the noise variance (not where a channel is
// inside an abs or sign factor of the same moment), and the noise that a formed state shares with
// its column across lags taken out of each moment (SharedNoise).

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "momentid/estimate.hpp"
#include "solve/rows.hpp"

namespace momentid {

namespace {

// A moment pair's share of an entry: E[instrument(t - s) function(t)] times `weight`, and
// times kappa[s - first] at each lag s where `kappa` is given (a shared noise's covariance).
struct PairTerm {
  Monomial instrument, function;
  double weight;
  const std::vector<double>* kappa;
};

// The shared-noise corrections of the pair (instrument, function) with weight `w`: for the one
// channel c1 of the instrument whose noise the function's channels share, -kappa_{c1 c2}(s) E[
// (instrument / c1)(t - s) dfunction/dc2 (t)] for each such c2. Throws std::invalid_argument
// when more than one factor of the instrument shares that noise, where the first-order term
// would not be the whole correction.
template <class Kappa>
void add_shared_noise(const SharedNoise& shared, const Monomial& instrument,
                      const Monomial& function, double w, Kappa kappa,
                      std::vector<PairTerm>& terms) {
  std::size_t c1 = instrument.size();
  int sharing = 0;
  for (std::size_t c = 0; c < instrument.size(); ++c) {
    if (instrument[c] == 0) continue;
    for (std::size_t c2 = 0; c2 < function.size(); ++c2) {
      if (function[c2] != 0 && shared.shared(c, c2)) {
        c1 = c;
        sharing += instrument[c];
        break;
      }
    }
  }
  if (sharing == 0) return;
  if (sharing > 1) {
    throw std::invalid_argument(
        "lagged_rows: an instrument holds more than one factor whose noise the function shares");
  }
  Monomial rest = instrument;
  rest[c1] = 0;
  for (std::size_t c2 = 0; c2 < function.size(); ++c2) {
    if (function[c2] == 0 || !shared.shared(c1, c2)) continue;
    Monomial derivative = function;
    derivative[c2] -= 1;
    terms.push_back({rest, derivative, -w * function[c2], &kappa(c1, c2)});
  }
}

}  // namespace

LaggedRows lagged_rows(const LaggedSystem& system, double dt, const std::vector<int>& channel,
                       const std::vector<double>& noise, int stencil, const SharedNoise& shared,
                       const std::map<Monomial, int>& products) {
  LaggedRows out;
  std::map<Moment, std::size_t> index;
  const std::vector<std::vector<std::size_t>> from = computed_from(*system.model, channel);
  std::size_t width = system.model->variables().size();
  for (const auto& [product, at] : products) width = std::max(width, product.size());
  const auto remap = [&](const Monomial& m) {
    Monomial out_m(width, 0);
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
  // Per (instrument, function) as read, the positions of its moments at lags first..last: the
  // index is searched once per pair, not once per lag.
  std::map<std::pair<Monomial, Monomial>, std::vector<std::size_t>> lag_positions;
  const auto lags = static_cast<std::size_t>(system.last_lag - system.first_lag + 1);
  // Per test function, the stencil of each derivative order applied to it at each lag.
  std::map<int, std::vector<double>> stenciled;
  const auto stencil_at = [&](int order, const LagTestFunction& phi) -> const std::vector<double>& {
    const auto [it, inserted] = stenciled.try_emplace(order);
    if (inserted) {
      const std::vector<double> w = stencil_weights(order, stencil);
      const int reach = stencil_reach(order, stencil);
      for (int s = system.first_lag; s <= system.last_lag; ++s) {
        double ws = 0;
        for (int j = -reach; j <= reach; ++j) {
          ws += w[static_cast<std::size_t>(j + reach)] * phi(s - j);
        }
        it->second.push_back(ws);
      }
    }
    return it->second;
  };
  // Per pair of channels sharing a noise, its covariance at each lag of the window.
  std::map<std::pair<std::size_t, std::size_t>, std::vector<double>> covariances;
  const auto kappa = [&](std::size_t c1, std::size_t c2) -> const std::vector<double>& {
    const auto [it, inserted] = covariances.try_emplace({c1, c2});
    if (inserted) {
      for (int s = system.first_lag; s <= system.last_lag; ++s) {
        it->second.push_back(shared.covariance(c1, c2, s));
      }
    }
    return it->second;
  };
  const auto entry = [&](const LagCombination& c, const LagTestFunction& phi) {
    MomentRows::Entry e;
    for (const auto& [f, weight] : c) {
      const std::vector<double>& ws = stencil_at(f.order, phi);
      const double scale = weight.to_double() / std::pow(dt, f.order);
      const auto instruments = noise_corrected(remap(f.instrument), noise);
      // The instrument, at an earlier time, carries noise independent of the function's, save
      // the noise the two share.
      const Monomial read = remap(f.function);
      const auto functions = noise_corrected(read, correctable_noise(read, noise, from));
      std::vector<PairTerm> terms;
      for (const auto& [instrument, wi] : instruments) {
        for (const auto& [function, wf] : functions) {
          terms.push_back({instrument, function, wi * wf, nullptr});
        }
      }
      if (!shared.empty()) {
        for (const auto& [instrument, wi] : instruments) {
          for (const auto& [function, wf] : functions) {
            add_shared_noise(shared, instrument, function, wi * wf, kappa, terms);
          }
        }
      }
      for (PairTerm& term : terms) {
        const auto product = products.find(term.function);
        if (product == products.end()) continue;
        term.function = Monomial(width, 0);
        term.function[static_cast<std::size_t>(product->second)] = 1;
      }
      // The pairs of terms (a constant pair has none): those first met here enter the index in
      // the order of the loops below, lag by lag.
      std::vector<const std::vector<std::size_t>*> pairs;
      std::vector<std::vector<std::size_t>*> met;
      std::vector<const PairTerm*> met_terms;
      for (const PairTerm& term : terms) {
        const auto zero = [](const Monomial& m) {
          return std::all_of(m.begin(), m.end(), [](int p) { return p == 0; });
        };
        if (zero(term.instrument) && zero(term.function)) {
          pairs.push_back(nullptr);
          continue;
        }
        const auto [it, inserted] = lag_positions.try_emplace({term.instrument, term.function});
        if (inserted) {
          met.push_back(&it->second);
          met_terms.push_back(&term);
        }
        pairs.push_back(&it->second);
      }
      for (int s = system.first_lag; s <= system.last_lag; ++s) {
        for (std::size_t k = 0; k < met.size(); ++k) {
          const Moment m = lagged_moment(met_terms[k]->instrument, met_terms[k]->function, s);
          const auto [it, inserted] = index.emplace(m, out.moments.size());
          if (inserted) out.moments.push_back(m);
          met[k]->push_back(it->second);
        }
      }
      for (std::size_t l = 0; l < lags; ++l) {
        for (std::size_t k = 0; k < terms.size(); ++k) {
          const PairTerm& term = terms[k];
          const double w = scale * ws[l] * term.weight * (term.kappa ? (*term.kappa)[l] : 1.0);
          if (const std::vector<std::size_t>* at = pairs[k]) {
            e.moments.emplace_back((*at)[l], w);
          } else {
            e.constant += w;
          }
        }
      }
    }
    return e;
  };
  for (const LagTestFunction& phi : system.test_functions) {
    stenciled.clear();
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
