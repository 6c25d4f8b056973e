#include "solve/rows.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <string>

namespace momentid {
namespace {

// E[(y + e)^p] over white Gaussian e of variance v is the expectation of y^p plus lower powers;
// the Hermite polynomial He_p(y; v) = sum_k (-1)^k p! / (k! (p - 2k)! 2^k) v^k y^(p - 2k) has
// E[He_p(y + e; v)] = E[y^p]. Returns the terms (power, weight) of He_p.
std::vector<std::pair<int, double>> hermite(int p, double v) {
  std::vector<std::pair<int, double>> out;
  double weight = 1;  // (-1)^k p! / (k! (p - 2k)! 2^k) v^k, by recurrence in k
  for (int k = 0; 2 * k <= p; ++k) {
    out.emplace_back(p - 2 * k, weight);
    weight *= -v * (p - 2 * k) * (p - 2 * k - 1) / (2.0 * (k + 1));
  }
  return out;
}

}  // namespace

// The noise of different variables is independent, so that the product of their polynomials is
// the polynomial of the product.
std::vector<std::pair<Monomial, double>> noise_corrected(const Monomial& m,
                                                         const std::vector<double>& noise) {
  std::vector<std::pair<Monomial, double>> terms{{Monomial(m.size(), 0), 1.0}};
  for (std::size_t c = 0; c < m.size(); ++c) {
    if (m[c] == 0) continue;
    std::vector<std::pair<Monomial, double>> next;
    for (const auto& [power, w] : hermite(m[c], c < noise.size() ? noise[c] : 0.0)) {
      for (const auto& [term, weight] : terms) {
        Monomial t = term;
        t[c] = power;
        next.emplace_back(t, weight * w);
      }
    }
    terms = std::move(next);
  }
  return terms;
}

std::vector<Monomial> moments_to_estimate(const MomentSystem& system) {
  std::vector<Monomial> out = system.moments;
  std::set<Monomial, MomentOrder> seen(out.begin(), out.end());
  const Monomial one(system.model->variables().size(), 0);
  auto add = [&](const Monomial& m) {
    if (m != one && seen.insert(m).second) out.push_back(m);
  };
  for (const DataIdentity& id : system.identities) {
    add(id.moment);
    for (const auto& [m, w] : id.value) add(m);
  }
  return out;
}

std::vector<std::vector<std::size_t>> computed_from(const Model& model,
                                                    const std::vector<int>& channel) {
  const int last = channel.empty() ? -1 : *std::max_element(channel.begin(), channel.end());
  std::vector<std::vector<std::size_t>> out(static_cast<std::size_t>(last + 1));
  for (std::size_t u = 0; u < model.variables().size(); ++u) {
    const Variable& variable = model.variables()[u];
    const int read = channel[u];
    if (variable.channel() || read < 0) continue;
    const VariableFunction& f = model.function_of(variable);
    for (const auto& [coefficient, monomial] : f.argument) {
      for (std::size_t v = 0; v < monomial.size(); ++v) {
        if (monomial[v] != 0 && channel[v] >= 0) {
          out[static_cast<std::size_t>(read)].push_back(static_cast<std::size_t>(channel[v]));
        }
      }
    }
  }
  return out;
}

std::vector<double> correctable_noise(const Monomial& m, std::vector<double> noise,
                                      const std::vector<std::vector<std::size_t>>& from) {
  for (std::size_t c = 0; c < m.size() && c < from.size(); ++c) {
    if (m[c] == 0) continue;
    for (std::size_t inside : from[c]) {
      if (inside < noise.size()) noise[inside] = 0;
    }
  }
  return noise;
}

std::map<Monomial, std::size_t> positions(const std::vector<Monomial>& moments) {
  std::map<Monomial, std::size_t> index;
  for (std::size_t k = 0; k < moments.size(); ++k) index.emplace(moments[k], k);
  return index;
}

MomentEstimates estimates_of(const std::vector<Monomial>& wanted,
                             const std::vector<Monomial>& given, const MomentEstimates& estimates,
                             const Model& model, const char* caller) {
  const std::string who = caller;
  if (given.size() != estimates.mean.size()) {
    throw std::invalid_argument(who + ": " + std::to_string(given.size()) + " moments named for " +
                                std::to_string(estimates.mean.size()) + " estimates");
  }
  std::map<Monomial, std::size_t> index;
  for (std::size_t k = 0; k < given.size(); ++k) {
    if (!index.emplace(given[k], k).second) {
      throw std::invalid_argument(who + ": " + format_moment(model, given[k]) + " is named twice");
    }
  }
  std::vector<std::size_t> columns;
  for (const Monomial& m : wanted) {
    const auto at = index.find(m);
    if (at == index.end()) {
      throw std::invalid_argument(who + ": no estimate of " + format_moment(model, m) +
                                  ", which the system needs");
    }
    columns.push_back(at->second);
  }
  MomentEstimates out;
  out.batch_intervals = estimates.batch_intervals;
  out.intervals = estimates.intervals;
  for (std::size_t k : columns) out.mean.push_back(estimates.mean[k]);
  for (const std::vector<double>& batch : estimates.batch_means) {
    if (batch.size() != given.size()) {
      throw std::invalid_argument(who + ": " + std::to_string(given.size()) +
                                  " moments named for batches of " + std::to_string(batch.size()));
    }
    std::vector<double>& means = out.batch_means.emplace_back();
    for (std::size_t k : columns) means.push_back(batch[k]);
  }
  return out;
}

std::optional<MomentRows::Entry> entry_of(const MomentCombination& combination,
                                          const std::map<Monomial, std::size_t>& index) {
  MomentRows::Entry out;
  for (const auto& [m, w] : combination) {
    if (m.degree() == 0 && !m.rate()) {
      out.constant += w.to_double();
    } else if (const auto at = index.find(m); at != index.end()) {
      out.moments.emplace_back(at->second, w.to_double());
    } else {
      return std::nullopt;
    }
  }
  return out;
}

MomentRows moment_rows(const MomentSystem& system, const std::map<Monomial, std::size_t>& index) {
  // Every moment of the equations is at `index`.
  const auto entry = [&](const MomentCombination& c) { return entry_of(c, index).value(); };
  MomentRows rows;
  for (const MomentEquation& eq : system.equations) {
    std::vector<MomentRows::Entry> a;
    for (const MomentCombination& c : eq.coefficients) a.push_back(entry(c));
    rows.a.push_back(std::move(a));
    rows.b.push_back(entry(eq.rhs));
  }
  return rows;
}

}  // namespace momentid
