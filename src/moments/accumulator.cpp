#include "momentid/accumulator.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "data/text.hpp"

// The accumulator's life: its runs and shards, its stretches and their merging. How it lays out
// its work is in accumulator_layout.cpp, the per-row work in accumulator_rows.cpp (a chunk of
// rows at a time with lags up to 60 rows: accumulator_chunks.cpp), its bytes in
// accumulator_bytes.cpp.

namespace momentid {

MomentAccumulator::MomentAccumulator(std::vector<Moment> moments, std::size_t states,
                                     std::size_t inputs, InputHold hold, std::size_t batches,
                                     HeldRule rule)
    : moments_(std::move(moments)),
      states_(states),
      inputs_(inputs),
      hold_(hold),
      rule_(hold == InputHold::kZeroOrderHold ? rule : HeldRule::kCubic),
      batches_(batches),
      stretches_(moments_.size()),
      max_stretches_(4 * std::max<std::size_t>(batches, 2)) {
  size_history();
  lay_out();
  open_stretch();
}

void MomentAccumulator::start_run() { finish_run(); }

void MomentAccumulator::continue_run() {
  finish_run();
  continued_ = true;
}

void MomentAccumulator::add_history(const double* rows, std::size_t count) {
  if (!continued_ || owned_rows_ > 0 || lookahead_rows_ > 0 || history_rows_ + count > max_lag_) {
    throw std::invalid_argument(
        "MomentAccumulator::add_history: " + std::to_string(history_rows_ + count) +
        " history rows, expected at most " + std::to_string(max_lag_) +
        " (the largest lag), right after continue_run()");
  }
  history_rows_ += count;
  push_rows(rows, count);
}

void MomentAccumulator::finish() { finish_run(); }

// Closes the interval between the last two rows given, the last of the run unless it lies in
// the lookahead (then close_interval skips it), and forgets the run.
void MomentAccumulator::finish_run() {
  if (plain_open_) {
    // The last row of the run ends the last interval of the plain sums: it has weight 1/2.
    plain_products(row_.data(), history_.data() + history_pos_);
    add_plain(row_, -0.5);
    plain_open_ = false;
  }
  if (chunked_ && run_rows_ >= 2) {
    close_chunked(next_close_, run_rows_ - 1);
  } else if (run_rows_ >= 2) {
    close_interval(run_rows_ - 2);
  }
  next_close_ = 0;
  flush();
  run_rows_ = 0;
  seen_rows_ = 0;
  continued_ = false;
  history_rows_ = 0;
  owned_rows_ = 0;
  lookahead_rows_ = 0;
}

void MomentAccumulator::add(const double* rows, std::size_t count) {
  if (lookahead_rows_ > 0) {
    throw std::logic_error(
        "MomentAccumulator::add after add_lookahead: the lookahead rows end the shard");
  }
  owned_rows_ += count;
  push_rows(rows, count);
}

void MomentAccumulator::add_lookahead(const double* rows, std::size_t count) {
  if (lookahead_rows_ + count > kLookaheadRows) {
    throw std::invalid_argument(
        "MomentAccumulator::add_lookahead: " + std::to_string(lookahead_rows_ + count) +
        " lookahead rows, expected at most " + std::to_string(kLookaheadRows));
  }
  lookahead_rows_ += count;
  push_rows(rows, count);
}

std::vector<MomentAccumulator::Stretch> MomentAccumulator::stretches() const {
  std::vector<Stretch> out;
  for (std::size_t s = 0; s < stretches_.size(); ++s) {
    out.push_back({{stretches_.sums(s), moments_.size()}, stretches_.intervals(s)});
  }
  return out;
}

// Adds the sums of the open stretch, kept in working order, to its stretch.
void MomentAccumulator::flush() {
  double* const sums = stretches_.sums(stretches_.size() - 1);
  for (std::size_t i = 0; i < open_sums_.size(); ++i) {
    sums[order_[i]] += open_sums_[i];
    open_sums_[i] = 0;
  }
}

// Adds up every stretch into one, followed by an open one.
void MomentAccumulator::collapse() {
  if (seen_rows_ > 0) {
    throw Error(
        "cannot collapse a moment accumulator in the middle of a run: call finish() on it "
        "first");
  }
  std::vector<double> whole(moments_.size(), 0.0);
  std::size_t intervals = 0;
  for (std::size_t s = 0; s < stretches_.size(); ++s) {
    for (std::size_t j = 0; j < whole.size(); ++j) whole[j] += stretches_.sums(s)[j];
    intervals += stretches_.intervals(s);
  }
  stretches_.truncate(0);
  if (intervals > 0) stretches_.append(whole.data(), intervals);
  open_stretch();
}

// Halves the number of stretches by adding neighbours; the open (last) stretch stays last. The
// emptied slots serve the stretches to come, so that a long pass takes no memory after its first
// compaction.
void MomentAccumulator::compact() {
  const std::size_t closed = stretches_.size() - 1;
  std::size_t kept = 0;
  for (std::size_t i = 0; i + 1 < closed; i += 2) {
    stretches_.add(i, i + 1);
    stretches_.swap(kept++, i);
  }
  // An odd one out starts the open stretch, which is then at most one old length long.
  if (closed % 2 == 1) stretches_.add(closed - 1, closed);
  stretches_.swap(kept++, closed % 2 == 1 ? closed - 1 : closed);
  stretches_.truncate(kept);
  stretch_length_ *= 2;
}

void MomentAccumulator::open_stretch() { stretches_.append(nullptr, 0); }

namespace {

const char* hold_name(InputHold hold, HeldRule rule) {
  if (hold == InputHold::kSample) return "sample";
  return rule == HeldRule::kCubic ? "zero-order hold" : "zero-order hold (trapezoidal)";
}

std::string channel_counts(std::size_t states, std::size_t inputs) {
  return data::plural(states, "state") + " and " + data::plural(inputs, "input");
}

}  // namespace

void MomentAccumulator::merge(const MomentAccumulator& other) {
  // A copy, also when `other` is this one: appending its own stretches would read them while they
  // grow.
  merge(MomentAccumulator(other));
}

void MomentAccumulator::merge(MomentAccumulator&& other) {
  if (other.seen_rows_ > 0) {
    throw Error(
        "cannot merge a moment accumulator in the middle of a run: call finish() on it first");
  }
  if (states_ != other.states_ || inputs_ != other.inputs_) {
    throw Error("cannot merge moment accumulators over different channels: " +
                channel_counts(states_, inputs_) + " here, " +
                channel_counts(other.states_, other.inputs_) + " in the other");
  }
  if (hold_ != other.hold_ || rule_ != other.rule_) {
    throw Error(std::string("cannot merge moment accumulators with different input holds: ") +
                hold_name(hold_, rule_) + " here, " + hold_name(other.hold_, other.rule_) +
                " in the other");
  }
  if (moments_.size() != other.moments_.size()) {
    throw Error("cannot merge moment accumulators of different moments: " +
                std::to_string(moments_.size()) + " here, " +
                std::to_string(other.moments_.size()) + " in the other");
  }
  for (std::size_t i = 0; i < moments_.size(); ++i) {
    if (moments_[i] != other.moments_[i]) {
      throw Error("cannot merge moment accumulators of different moments: moment " +
                  std::to_string(i) + " is " + to_string(moments_[i]) + " here, " +
                  to_string(other.moments_[i]) + " in the other");
    }
  }
  finish_run();
  if (stretches_.intervals(stretches_.size() - 1) == 0) stretches_.truncate(stretches_.size() - 1);
  stretches_.take(std::move(other.stretches_));
  intervals_ += other.intervals_;
  open_stretch();
  while (stretches_.size() > max_stretches_) compact();
}

}  // namespace momentid
