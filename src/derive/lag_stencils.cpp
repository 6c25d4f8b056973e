// How a lag function is read from the data: the moment keys of C[ψ;F](s) at each lag, and
// the central stencils (Fornberg's weights) that take its derivatives in s.

#include <algorithm>
#include <stdexcept>
#include <string>

#include "momentid/lagged.hpp"

namespace momentid {

int stencil_reach(int order, int reach) { return order <= 2 ? reach : reach + (order - 1) / 2; }

std::vector<double> stencil_weights(int order, int reach) {
  if (order < 0 || order > kMaxEliminatedOrder || reach < 1) {
    throw std::invalid_argument("stencil_weights: order " + std::to_string(order) + ", reach " +
                                std::to_string(reach) + ": expected an order from 0 to " +
                                std::to_string(kMaxEliminatedOrder) + " and a reach from 1");
  }
  // Fornberg's recursion for the weights at the points -R..R of every derivative up to `order`
  // at 0 (B. Fornberg, Math. Comp. 51 (1988) 699-706).
  const int r = stencil_reach(order, reach);
  const int n = 2 * r + 1;
  std::vector<std::vector<double>> c(static_cast<std::size_t>(order + 1),
                                     std::vector<double>(static_cast<std::size_t>(n), 0.0));
  const auto x = [&](int i) { return static_cast<double>(i - r); };
  c[0][0] = 1;
  double c1 = 1;
  for (int i = 1; i < n; ++i) {
    const int top = std::min(i, order);
    double c2 = 1;
    for (int j = 0; j < i; ++j) {
      const double c3 = x(i) - x(j);
      c2 *= c3;
      const auto ui = static_cast<std::size_t>(i), uj = static_cast<std::size_t>(j);
      if (j == i - 1) {
        for (int k = top; k >= 1; --k) {
          const auto uk = static_cast<std::size_t>(k);
          c[uk][ui] = c1 * (k * c[uk - 1][ui - 1] - x(i - 1) * c[uk][ui - 1]) / c2;
        }
        c[0][ui] = -c1 * x(i - 1) * c[0][ui - 1] / c2;
      }
      for (int k = top; k >= 1; --k) {
        const auto uk = static_cast<std::size_t>(k);
        c[uk][uj] = (x(i) * c[uk][uj] - k * c[uk - 1][uj]) / c3;
      }
      c[0][uj] = x(i) * c[0][uj] / c3;
    }
    c1 = c2;
  }
  return c[static_cast<std::size_t>(order)];
}

Moment lagged_moment(const Monomial& instrument, const Monomial& function, int lag) {
  std::vector<MomentFactor> factors;
  for (std::size_t v = 0; v < instrument.size(); ++v) {
    if (instrument[v] != 0) factors.push_back({static_cast<int>(v), instrument[v], lag});
    if (function[v] != 0) factors.push_back({static_cast<int>(v), function[v], 0});
  }
  return Moment(std::move(factors));
}

}  // namespace momentid
