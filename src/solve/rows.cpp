#include "solve/rows.hpp"

#include <set>
#include <stdexcept>
#include <string>

namespace momentid {

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
