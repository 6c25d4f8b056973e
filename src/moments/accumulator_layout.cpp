// How a MomentAccumulator lays out its work before the first row: the table of channel powers,
// the working order of the moments, and their grouping into blocks of products of contiguous
// rows that the per-row kernels (accumulator_rows.cpp) sweep.

#include "moments/accumulator_layout.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

#include "data/text.hpp"

namespace momentid {

// Checks the moments' channels and sizes the power table and the history.
void MomentAccumulator::size_history() {
  const std::size_t variables = states_ + inputs_;
  for (const Moment& m : moments_) {
    for (const MomentFactor& f : m.factors()) {
      if (static_cast<std::size_t>(f.channel) >= variables) {
        throw std::invalid_argument(
            "moment " + to_string(m) + ": the factor " + to_string(f) + " names channel " +
            std::to_string(f.channel) + ", expected a channel below " + std::to_string(variables) +
            " (" + data::plural(states_, "state") + ", " + data::plural(inputs_, "input") + ")");
      }
      max_lag_ = std::max(max_lag_, static_cast<std::size_t>(f.lag));
    }
  }
  max_power_.assign(variables, 1);
  for (const Moment& m : moments_) {
    for (const MomentFactor& f : m.factors()) {
      max_power_[f.channel] = std::max(max_power_[f.channel], f.power);
    }
  }
  std::size_t offset = 0;
  for (int p : max_power_) {
    power_offset_.push_back(offset);
    offset += static_cast<std::size_t>(p) + 1;
  }
  // Every power of every channel over the last max_lag_ + 2 rows (the moments of the row before
  // the newest are recomputed at the ends of the stretches), newest first, stored twice in a row
  // so that the rows back from any start are contiguous.
  history_.assign(offset * 2 * (max_lag_ + 2), 1.0);
}

// A moment is read with its most lagged factor max_lag_ rows back: the products at every lag
// then share one window of times for that factor (the instrument), and a stencil over lags of
// C[ψ;F](s) = E[ψ(t − s) F(t)] is exactly the stencil applied to F at each instrument time, with
// no end effects; reading F at a fixed window instead would leave end terms that a derivative in
// s multiplies by 1/dt^2.
std::vector<MomentAccumulator::Layout> MomentAccumulator::layouts() const {
  std::vector<Layout> out(moments_.size());
  for (std::size_t i = 0; i < moments_.size(); ++i) {
    Layout& l = out[i];
    const std::size_t shift = max_lag_ - static_cast<std::size_t>(moments_[i].max_lag());
    bool has_input = false;
    for (bool state_part : {true, false}) {
      for (const MomentFactor& f : moments_[i].factors()) {
        if ((static_cast<std::size_t>(f.channel) < states_) != state_part) continue;
        l.indices.push_back(power_offset_[f.channel] + static_cast<std::size_t>(f.power));
        l.lags.push_back(static_cast<std::size_t>(f.lag) + shift);
        has_input = has_input || !state_part;
      }
      if (state_part) l.state_factors = l.indices.size();
    }
    if (moments_[i].is_increment()) {
      l.kind = Layout::kIncrement;  // the whole product at each row, kept in the rings
      l.state_factors = l.indices.size();
    } else if (hold_ == InputHold::kZeroOrderHold && has_input) {
      l.kind = Layout::kHeld;
    }
  }
  return out;
}

void MomentAccumulator::lay_out() {
  const std::vector<Layout> all = layouts();
  // The moments are worked on in an order that puts the held ones first, then the increments,
  // and lines up the same factors at successive lags, so that blocks of them are products of
  // contiguous rows.
  order_.resize(moments_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
  std::stable_sort(order_.begin(), order_.end(), [&](std::size_t x, std::size_t y) {
    const Layout& a = all[x];
    const Layout& b = all[y];
    if (a.kind != b.kind) return a.kind < b.kind;
    return std::tie(a.state_factors, a.indices, a.lags) <
           std::tie(b.state_factors, b.indices, b.lags);
  });
  const auto count = [&](Layout::Kind kind) {
    return static_cast<std::size_t>(
        std::count_if(all.begin(), all.end(), [&](const Layout& l) { return l.kind == kind; }));
  };
  increments_begin_ = count(Layout::kHeld);
  ringed_count_ = increments_begin_ + count(Layout::kIncrement);
  const std::size_t k = moments_.size();
  open_sums_.assign(k, 0.0);
  // A chunk carries the max_lag_ + 4 rows before it: beyond half a chunk, copying them would
  // cost more than the chunk saves (a default window of lags to 300 on 10^5 rows: 18% more time),
  // and such moments go row by row.
  chunked_ = max_lag_ + 4 <= kChunk / 2 && std::all_of(all.begin(), all.end(), [](const Layout& l) {
               return l.indices.size() <= kChunkFactors;
             });
  if (chunked_) {
    lay_out_chunks(all);
    return;
  }
  group_blocks(all);
  choose_singles();
  state_ring_.assign(4 * ringed_count_, 0.0);
  input_ring_.assign(4 * ringed_count_, 0.0);
  row_.assign(k, 0.0);
  previous_row_.assign(k, 0.0);
}

// Runs of moments in working order with the same kind and factors, whose lags step by -1, 0 or
// 1 from one to the next, the same steps throughout the run, become one block.
void MomentAccumulator::group_blocks(const std::vector<Layout>& all) {
  const std::size_t span = 2 * (max_lag_ + 2);
  for (std::size_t q = 0; q < order_.size();) {
    const Layout& first = all[order_[q]];
    std::vector<long> steps;
    std::size_t end = q + 1;
    for (; end < order_.size(); ++end) {
      const Layout& prev = all[order_[end - 1]];
      const Layout& next = all[order_[end]];
      if (next.kind != first.kind || next.state_factors != first.state_factors ||
          next.indices != first.indices) {
        break;
      }
      std::vector<long> d(next.lags.size());
      bool unit = true;
      for (std::size_t f = 0; f < d.size(); ++f) {
        d[f] = static_cast<long>(next.lags[f]) - static_cast<long>(prev.lags[f]);
        unit = unit && d[f] >= -1 && d[f] <= 1;
      }
      if (!unit || (end > q + 1 && d != steps)) break;
      steps = d;
    }
    Block block{q, end - q, first.state_factors, {}};
    for (std::size_t f = 0; f < first.indices.size(); ++f) {
      block.factors.push_back({first.indices[f] * span + first.lags[f],
                               steps.empty() ? 0 : static_cast<int>(steps[f])});
    }
    blocks_.push_back(std::move(block));
    q = end;
  }
}

// Blocks of one moment with at most four factors go to the flat lists of singles.
void MomentAccumulator::choose_singles() {
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    const Block& b = blocks_[i];
    const bool ringed = b.begin < ringed_count_;
    const std::size_t n = b.factors.size();
    const bool fits = std::all_of(b.factors.begin(), b.factors.end(), [](const BlockFactor& f) {
      return f.offset <= std::numeric_limits<std::uint32_t>::max();
    });
    if (b.size == 1 && n <= 4 && fits) {
      Single single{static_cast<std::uint32_t>(b.begin),
                    static_cast<std::uint32_t>(b.state_factors),
                    static_cast<std::uint32_t>(n),
                    {}};
      for (std::size_t f = 0; f < n; ++f) {
        single.offsets[f] = static_cast<std::uint32_t>(b.factors[f].offset);
      }
      (ringed ? held_singles_ : plain_singles_).push_back(single);
    } else {
      (ringed ? held_blocks_ : plain_blocks_).push_back(i);
    }
  }
}

}  // namespace momentid
