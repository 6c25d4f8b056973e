// Moment estimates from an accumulator's stretches: the overall means and the means over
// contiguous batches of the record.

#include <algorithm>

#include "momentid/accumulator.hpp"

namespace momentid {

MomentEstimates estimates(const MomentAccumulator& accumulator, std::size_t batches) {
  const std::size_t k = accumulator.moments().size();
  std::vector<MomentAccumulator::Stretch> full = accumulator.stretches();
  std::erase_if(full, [](const MomentAccumulator::Stretch& s) { return s.intervals == 0; });
  MomentEstimates out;
  out.mean.assign(k, 0.0);
  out.intervals = accumulator.intervals();
  const std::size_t b = std::max<std::size_t>(1, std::min(batches, full.size()));
  std::vector<std::vector<double>> sums(b, std::vector<double>(k, 0.0));
  std::vector<std::size_t> counts(b, 0);
  // A stretch goes to the batch its middle falls in, so that batches hold nearly equal numbers
  // of intervals.
  std::size_t before = 0;
  for (std::size_t i = 0; i < full.size(); ++i) {
    const std::size_t middle = before + full[i].intervals / 2;
    before += full[i].intervals;
    const std::size_t batch =
        std::min(b - 1, out.intervals > 0 ? middle * b / out.intervals : std::size_t{0});
    for (std::size_t j = 0; j < k; ++j) {
      sums[batch][j] += full[i].sums[j];
      out.mean[j] += full[i].sums[j];
    }
    counts[batch] += full[i].intervals;
  }
  if (out.intervals > 0) {
    for (double& m : out.mean) m /= static_cast<double>(out.intervals);
  }
  std::vector<std::vector<double>> means;
  for (std::size_t i = 0; i < b; ++i) {
    if (counts[i] == 0) continue;
    for (double& s : sums[i]) s /= static_cast<double>(counts[i]);
    means.push_back(std::move(sums[i]));
    out.batch_intervals.push_back(counts[i]);
  }
  out.batch_means = std::move(means);
  return out;
}

}  // namespace momentid
