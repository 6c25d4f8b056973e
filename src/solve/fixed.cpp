#include "solve/fixed.hpp"

#include "solve/numbers.hpp"

namespace momentid {
namespace {

// Values for the free parameters (`free`, in order) spread over all, `given` for the fixed ones.
template <typename T, typename Given>
std::vector<T> spread(const std::vector<T>& free, const std::vector<std::optional<double>>& fixed,
                      Given given) {
  std::vector<T> out;
  for (std::size_t p = 0, k = 0; p < fixed.size(); ++p) {
    out.push_back(fixed[p] ? given(p) : free[k++]);
  }
  return out;
}

// A parameters x parameters matrix of the free ones over all, NaN in the fixed rows and columns.
std::vector<std::vector<double>> spread_matrix(const std::vector<std::vector<double>>& free,
                                               const std::vector<std::optional<double>>& fixed) {
  std::vector<std::vector<double>> out(fixed.size(), std::vector<double>(fixed.size(), kNaN));
  std::vector<std::size_t> index;
  for (std::size_t p = 0; p < fixed.size(); ++p) {
    if (!fixed[p]) index.push_back(p);
  }
  for (std::size_t i = 0; i < index.size(); ++i) {
    for (std::size_t j = 0; j < index.size(); ++j) out[index[i]][index[j]] = free[i][j];
  }
  return out;
}

}  // namespace

MomentRows without_fixed(const MomentRows& rows, const std::vector<std::optional<double>>& fixed) {
  MomentRows out;
  for (std::size_t r = 0; r < rows.a.size(); ++r) {
    std::vector<MomentRows::Entry> row;
    MomentRows::Entry b = rows.b[r];
    for (std::size_t p = 0; p < rows.a[r].size(); ++p) {
      const MomentRows::Entry& e = rows.a[r][p];
      if (!fixed[p]) {
        row.push_back(e);
        continue;
      }
      b.constant -= *fixed[p] * e.constant;
      for (const auto& [k, w] : e.moments) b.moments.emplace_back(k, -*fixed[p] * w);
    }
    out.a.push_back(std::move(row));
    out.b.push_back(std::move(b));
  }
  return out;
}

Estimate with_fixed(Estimate free, const std::vector<std::string>& names,
                    const std::vector<std::optional<double>>& fixed) {
  const auto known = [&](std::size_t p) {
    return ParameterEstimate{names[p], *fixed[p], 0, *fixed[p], *fixed[p], true, true};
  };
  for (Fit* fit : {&free.least_squares, free.optimal ? &*free.optimal : nullptr}) {
    if (!fit) continue;
    fit->parameters = spread(fit->parameters, fixed, known);
    if (!fit->correlation.empty()) fit->correlation = spread_matrix(fit->correlation, fixed);
  }
  for (std::vector<double>& row : free.error_batches) {
    row = spread(row, fixed, [](std::size_t) { return 0.0; });
  }
  return free;
}

}  // namespace momentid
