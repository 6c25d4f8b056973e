#include "moments/shard.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <deque>
#include <optional>

#include "moments/blocks.hpp"
#include "moments/integration.hpp"

namespace momentid {
namespace {

// Whether a computed channel's argument holds an input (then it holds inputs alone).
bool of_inputs(const ComputedChannel& c, std::size_t states) {
  for (const auto& [coefficient, monomial] : c.argument) {
    for (std::size_t i = states; i < monomial.size(); ++i) {
      if (monomial[i] != 0) return true;
    }
  }
  return false;
}

double value_of(const ComputedChannel& c, const double* row) {
  double p = 0;
  for (const auto& [coefficient, monomial] : c.argument) {
    double term = coefficient;
    for (std::size_t i = 0; i < monomial.size(); ++i) {
      for (int e = 0; e < monomial[i]; ++e) term *= row[i];
    }
    p += term;
  }
  switch (c.kind) {
    case ComputedChannel::Kind::kAbs:
      return std::abs(p);
    case ComputedChannel::Kind::kSign:
      return p > 0 ? 1.0 : p < 0 ? -1.0 : 0.0;
    case ComputedChannel::Kind::kPolynomial:
      break;
  }
  return p;
}

// The computed channels that a filter takes with the channels read (DataOptions::Integration):
// those whose argument holds channels filtered alone, no formed one.
std::vector<std::size_t> filtered_whole(const DataOptions& options) {
  std::vector<std::size_t> out;
  if (!options.integration) return out;
  const std::vector<int>& integrals = options.integration->integrals;
  for (std::size_t k = 0; k < options.computed.size(); ++k) {
    bool raw = true;
    for (const auto& [coefficient, monomial] : options.computed[k].argument) {
      for (std::size_t c = 0; c < monomial.size(); ++c)
        raw &= monomial[c] == 0 || integrals[c] == 0;
    }
    if (raw) out.push_back(k);
  }
  return out;
}

// The rows in the accumulator's columns (ChannelLayout): the channels read, with the computed
// ones. Without computed channels the rows are used as they are. The rows taken may carry
// computed channels after the channels read (`carried`, in their order), which are copied.
class Widen {
 public:
  Widen(const PassSetup& setup, const std::vector<std::size_t>& carried)
      : read_(setup.states + setup.inputs),
        stride_(read_ + carried.size()),
        computed_(setup.options->computed),
        column_(setup.layout.column),
        carried_at_(computed_.size(), 0) {
    for (std::size_t j = 0; j < carried.size(); ++j) carried_at_[carried[j]] = read_ + j;
  }

  std::size_t width() const { return column_.size(); }

  const double* apply(const double* rows, std::size_t count) {
    if (computed_.empty()) return rows;
    out_.resize(count * width());
    for (std::size_t r = 0; r < count; ++r) {
      const double* in = rows + r * stride_;
      double* out = out_.data() + r * width();
      for (std::size_t c = 0; c < read_; ++c) out[column_[c]] = in[c];
      for (std::size_t k = 0; k < computed_.size(); ++k) {
        out[column_[read_ + k]] =
            carried_at_[k] > 0 ? in[carried_at_[k]] : value_of(computed_[k], in);
      }
    }
    return out_.data();
  }

 private:
  std::size_t read_, stride_;
  const std::vector<ComputedChannel>& computed_;
  const std::vector<std::size_t>& column_;
  std::vector<std::size_t> carried_at_;  // per computed channel: its place in a row taken, or 0
  std::vector<double> out_;
};

// Pairs input row n with state row n + shift within a run (`--input-shift`), for data whose
// input and state channels are not aligned in time. Rows without a partner are dropped.
class InputShift {
 public:
  InputShift(std::size_t states, std::size_t inputs, long shift)
      : states_(states), inputs_(inputs), shift_(shift) {}

  void start_run() { past_.clear(); }

  // The shifted rows for `count` new rows (states, then inputs).
  const std::vector<double>& apply(const double* rows, std::size_t count) {
    const std::size_t width = states_ + inputs_;
    const std::size_t lag = static_cast<std::size_t>(shift_ < 0 ? -shift_ : shift_);
    out_.clear();
    for (std::size_t r = 0; r < count; ++r) {
      const double* row = rows + r * width;
      if (past_.size() == lag) {
        // shift > 0: the states of this row with the inputs of `lag` rows ago; shift < 0: the
        // states of `lag` rows ago with the inputs of this row.
        const double* early = lag == 0 ? row : past_.front().data();
        const double* states = shift_ >= 0 ? row : early;
        const double* inputs = shift_ >= 0 ? early : row;
        out_.insert(out_.end(), states, states + states_);
        out_.insert(out_.end(), inputs + states_, inputs + width);
      }
      if (lag > 0) {
        if (past_.size() == lag) past_.pop_front();
        past_.emplace_back(row, row + width);
      }
    }
    return out_;
  }

 private:
  std::size_t states_, inputs_;
  long shift_;
  std::deque<std::vector<double>> past_;
  std::vector<double> out_;
};

// Every `stride`-th row of each run from row `phase` on (DataOptions::stride).
class Decimate {
 public:
  Decimate(std::size_t width, std::size_t stride, std::size_t phase)
      : width_(width), stride_(stride), phase_(phase) {}

  void start_run() { row_ = 0; }

  const std::vector<double>& apply(const double* rows, std::size_t count) {
    out_.clear();
    for (std::size_t r = 0; r < count; ++r, ++row_) {
      if (row_ >= phase_ && (row_ - phase_) % stride_ == 0) {
        out_.insert(out_.end(), rows + r * width_, rows + (r + 1) * width_);
      }
    }
    return out_;
  }

 private:
  std::size_t width_, stride_, phase_, row_ = 0;
  std::vector<double> out_;
};

// One shard's pass over its blocks.
class ShardPass {
 public:
  explicit ShardPass(const PassSetup& setup)
      : options_(*setup.options),
        channels_(setup.states + setup.inputs),
        out_{MomentAccumulator(setup.moments, setup.layout.states, setup.layout.inputs, setup.hold,
                               setup.batches, options_.held_rule),
             LagSums(channels_, options_.lags, options_.point_moments)},
        filtered_whole_(filtered_whole(options_)),
        widen_(setup, filtered_whole_),
        shift_(setup.layout.states, setup.layout.inputs, options_.input_shift),
        decimate_(widen_.width(), options_.stride, options_.phase),
        history_values_(out_.moments.max_lag() * widen_.width()) {
    if (options_.integration) {
      DataOptions::Integration filter = *options_.integration;
      filter.integrals.resize(channels_ + filtered_whole_.size(), 0);
      integration_.emplace(filter);
    }
  }

  // Takes the next block; true if it holds rows of the shard's own.
  bool take(DataBlock& block) {
    subtract_offsets(block);
    if (integration_) return take_filtered(block);
    switch (block.zone) {
      case RowZone::kBefore:
        before(block);
        return false;
      case RowZone::kAfter:
        if (owned_) {
          out_.moments.add_lookahead(widen_.apply(block.values.data(), block.rows), block.rows);
        }
        return false;
      case RowZone::kOwned:
        break;
    }
    own(block);
    return true;
  }

  ShardState finish(bool collapse) {
    if (integration_) flush_run();
    out_.moments.finish();
    if (collapse) out_.moments.collapse();
    return std::move(out_);
  }

 private:
  void subtract_offsets(DataBlock& block) const {
    if (options_.offsets.empty()) return;
    double* values = block.values.data();
    for (std::size_t r = 0; r < block.rows; ++r) {
      for (std::size_t c = 0; c < channels_; ++c) values[r * channels_ + c] -= options_.offsets[c];
    }
  }

  // Filters the rows (a shard is a whole file: every block its own); the filtered rows that are
  // complete go on as a block of the same run, the first of a run starting it. False when none
  // went on.
  bool take_filtered(const DataBlock& block) {
    bool took = false;
    if (block.run_starts) {
      took = flush_run();
      integration_->start_run();
      run_pending_ = true;
    }
    filtered_.values.clear();
    integration_->push(with_filtered_whole(block), block.rows, filtered_.values);
    return emit_filtered() || took;
  }

  // The block's rows with the computed channels the filter takes after the channels read.
  const double* with_filtered_whole(const DataBlock& block) {
    if (filtered_whole_.empty()) return block.values.data();
    const std::size_t stride = channels_ + filtered_whole_.size();
    wide_.resize(block.rows * stride);
    for (std::size_t r = 0; r < block.rows; ++r) {
      const double* in = block.values.data() + r * channels_;
      double* out = wide_.data() + r * stride;
      std::copy(in, in + channels_, out);
      for (std::size_t j = 0; j < filtered_whole_.size(); ++j) {
        out[channels_ + j] = value_of(options_.computed[filtered_whole_[j]], in);
      }
    }
    return wide_.data();
  }

  // The channels read of the filtered rows, without the computed ones they carry.
  const double* channels_of(const DataBlock& block) {
    if (filtered_whole_.empty()) return block.values.data();
    const std::size_t stride = channels_ + filtered_whole_.size();
    narrow_.resize(block.rows * channels_);
    for (std::size_t r = 0; r < block.rows; ++r) {
      std::copy_n(block.values.data() + r * stride, channels_, narrow_.data() + r * channels_);
    }
    return narrow_.data();
  }

  // The filtered rows of the run's last inputs.
  bool flush_run() {
    filtered_.values.clear();
    integration_->flush(filtered_.values);
    return emit_filtered();
  }

  bool emit_filtered() {
    filtered_.rows = filtered_.values.size() / (channels_ + filtered_whole_.size());
    if (filtered_.rows == 0) return false;
    filtered_.run_starts = run_pending_;
    run_pending_ = false;
    own(filtered_);
    return true;
  }

  // Rows of the run before the shard: history for the lagged factors and the lagged pairs.
  void before(const DataBlock& block) {
    const double* const values = block.values.data();
    if (block.run_starts) {
      history_.clear();
      out_.lags.start_run();
    }
    const double* wide = widen_.apply(values, block.rows);
    history_.insert(history_.end(), wide, wide + block.rows * widen_.width());
    if (history_.size() > history_values_) {
      history_.erase(history_.begin(),
                     history_.end() - static_cast<std::ptrdiff_t>(history_values_));
    }
    out_.lags.add_history(values, block.rows);
  }

  void own(const DataBlock& block) {
    const double* const values = block.values.data();
    if (block.run_starts) {
      shift_.start_run();
      decimate_.start_run();
      out_.moments.start_run();
      out_.lags.start_run();
      ++out_.runs;
    } else if (!owned_) {
      out_.moments.continue_run();
      if (!history_.empty()) {
        out_.moments.add_history(history_.data(), history_.size() / widen_.width());
      }
    }
    owned_ = true;
    const double* rows = widen_.apply(values, block.rows);
    std::size_t count = block.rows;
    if (options_.input_shift != 0) {
      const std::vector<double>& shifted = shift_.apply(rows, count);
      rows = shifted.data();
      count = shifted.size() / widen_.width();
    }
    if (options_.stride > 1) {
      const std::vector<double>& kept = decimate_.apply(rows, count);
      rows = kept.data();
      count = kept.size() / widen_.width();
    }
    out_.moments.add(rows, count);
    out_.lags.add(channels_of(block), block.rows);
    out_.rows += block.rows;
  }

  const DataOptions& options_;
  std::size_t channels_;
  ShardState out_;
  std::vector<std::size_t> filtered_whole_;  // the computed channels the filter takes (in order)
  Widen widen_;
  InputShift shift_;
  Decimate decimate_;
  std::vector<double> history_;  // of the current run, before the shard
  std::size_t history_values_;
  bool owned_ = false;
  std::optional<IntegrationFilter> integration_;
  DataBlock filtered_;
  std::vector<double> wide_, narrow_;  // the rows with and without the computed channels
  bool run_pending_ = false;
};

}  // namespace

ChannelLayout::ChannelLayout(std::size_t read_states, std::size_t read_inputs,
                             const std::vector<ComputedChannel>& computed)
    : column(read_states + read_inputs + computed.size()) {
  std::vector<std::size_t> continuous, held;  // computed channel indices
  for (std::size_t k = 0; k < computed.size(); ++k) {
    (of_inputs(computed[k], read_states) ? held : continuous).push_back(k);
  }
  states = read_states + continuous.size();
  inputs = read_inputs + held.size();
  std::size_t next = 0;
  for (std::size_t c = 0; c < read_states; ++c) column[c] = next++;
  for (std::size_t k : continuous) column[read_states + read_inputs + k] = next++;
  for (std::size_t c = read_states; c < read_states + read_inputs; ++c) column[c] = next++;
  for (std::size_t k : held) column[read_states + read_inputs + k] = next++;
}

ShardState read_shard(DataReader& reader, bool whole, const PassSetup& setup, bool pipelined,
                      std::atomic<std::size_t>& rows_done, std::atomic<double>& fraction) {
  ShardPass pass(setup);
  for_each_block(reader, pipelined, [&](DataBlock& block) {
    if (!pass.take(block)) return;
    rows_done += block.rows;
    // A part of a file cannot tell how far it is; a whole file can.
    if (setup.options->record.control.progress && whole) {
      fraction = reader.fraction_read().value_or(0);
    }
  });
  ShardState out = pass.finish(setup.collapse);
  out.summary = {reader.steps(), reader.time_step(), reader.missing()};
  return out;
}

}  // namespace momentid
