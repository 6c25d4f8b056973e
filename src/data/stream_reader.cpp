#include "data/stream_reader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/decimal.hpp"
#include "common/number.hpp"
#include "data/text.hpp"
#include "moments/kernel.hpp"

namespace momentid::data {
namespace {

// Relative tolerance of a time step: far below a missing sample or a changed step.
constexpr double kStepTolerance = 1e-6;
// Steps are differences of times, compared with the first step: rounding of the times adds an
// error proportional to |t|. Four roundings of float32 time stamps (2^-24 of |t| each), which
// also covers times printed with seven or more significant digits.
constexpr double kTimeRounding = 4 * 5.9604644775390625e-8;

}  // namespace

namespace {

// step_allowance past its part that does not depend on the times (`fixed`), for a double and for
// four lanes (Four) alike.
template <class T>
T time_allowance(double fixed, T t, T previous) {
  using P = TimePrecision;
  return fixed + kTimeRounding * P::larger(P::magnitude(t), P::magnitude(previous));
}

}  // namespace

double StreamReader::fixed_allowance(double reference) const {
  // Times printed to a few decimals: one unit in the last place, but never half a step, so that
  // a missing or doubled sample is refused whatever the precision.
  const double printed = std::min(precision_.unit(), reference / 2);
  return kStepTolerance * reference + printed;
}

double StreamReader::step_allowance(double t, double previous, double reference) const {
  return time_allowance(fixed_allowance(reference), t, previous);
}

bool to_run(double value, long& run) {
  constexpr double kLimit = 9.0e18;
  if (!(std::abs(value) < kLimit) || value != std::trunc(value)) return false;
  run = static_cast<long>(value);
  return true;
}

bool StreamReader::next(DataBlock& block, std::size_t max_rows) {
  try {
    return next_rows(block, max_rows);
  } catch (const DataError& e) {
    // A part's layout may number lines from where it began reading.
    const long long skipped = lines_skipped();
    if (skipped == 0) throw;
    SourceLocation at = e.location();
    at.line = clamp_to_int(at.line + skipped);
    throw DataError(at, e.message());
  }
}

StreamReader::Bounds StreamReader::row_bounds(std::uint64_t rows, const ColumnRequest::Part& part,
                                              std::uint64_t& first) {
  // rows * k / count, without overflow for fewer than 2^32 parts.
  const auto cut = [&](std::uint64_t k) {
    return rows / part.count * k + rows % part.count * k / part.count;
  };
  Bounds bounds{cut(part.index), part.index + 1 == part.count
                                     ? std::numeric_limits<std::uint64_t>::max()
                                     : cut(part.index + 1)};
  first = bounds.begin - std::min<std::uint64_t>(part.before, bounds.begin);
  return bounds;
}

// The rows that follow the block's first as it does, taken at once (read_rows): the block's
// zone owned, no run column, no row dropped before them, and, with a time column, the first
// step known. Rows from the first whose time step read_row's checks would question on are
// given back, to be read one by one. Returns how many were taken.
std::size_t StreamReader::take_rows(DataBlock& block, std::size_t max_rows) {
  const bool timed = map_.time >= 0 && !request_.dt;
  if (!takes_many_rows_ || block.rows == 0 || block.zone != RowZone::kOwned || map_.run >= 0 ||
      dropped_ || joined_ || (timed && !step_)) {
    return 0;
  }
  std::size_t room = max_rows - block.rows;
  if (bounds_) room = std::min<std::uint64_t>(room, bounds_->end - (row_position() + 1));
  if (room == 0) return 0;
  const std::size_t width = request_.names.size();
  double* const rows = block.values.data() + block.rows * width;
  times_.resize(room);
  std::size_t n = read_rows(rows, times_.data(), room);
  for (std::size_t r = 0; r < n; ++r) {
    for (const auto& [to, from] : map_.copies) rows[r * width + to] = rows[r * width + from];
  }
  if (timed) {
    const std::size_t steady = steady_steps(times_.data(), n);
    if (steady < n) {
      unread_rows(n - steady);
      n = steady;
    }
  }
  block.rows += n;
  return n;
}

RowZone StreamReader::zone_of_last_row() const {
  const std::uint64_t position = row_position();
  if (position < bounds_->begin) return RowZone::kBefore;
  return position < bounds_->end ? RowZone::kOwned : RowZone::kAfter;
}

bool StreamReader::next_rows(DataBlock& block, std::size_t max_rows) {
  const std::size_t width = request_.names.size();
  const bool parted = request_.part.count > 1;
  if (parted && !bounds_) bounds_ = seek_part(request_.part);
  // A wide record's blocks hold fewer rows: memory stays flat whatever the width.
  max_rows = std::clamp<std::size_t>(
      max_rows, 1, std::max<std::size_t>(1, kBlockValues / std::max<std::size_t>(width, 1)));
  block.values.resize(max_rows * width);
  block.rows = 0;
  block.zone = RowZone::kOwned;
  if (has_pending_) {
    std::copy(pending_.begin(), pending_.end(), block.values.begin());
    block.run = current_run_;
    block.run_starts = pending_run_starts_;
    block.zone = pending_zone_;
    block.rows = 1;
    has_pending_ = false;
  }
  RowKeys keys;
  while (block.rows < max_rows && !part_done_) {
    if (take_rows(block, max_rows) > 0) continue;
    double* const row = block.values.data() + block.rows * width;
    keys.missing_field = -1;
    if (!read_row(row, keys)) {
      if (parted) {
        part_done_ = true;
      } else {
        finish(rows_read_ + block.rows);
      }
      break;
    }
    if (keys.missing_field >= 0) {
      if (!missing_.first) missing_.first = field_location(keys.missing_field);
      ++missing_.rows;
      dropped_ = started_;
      continue;
    }
    for (const auto& [to, from] : map_.copies) row[to] = row[from];
    const bool split = dropped_ && request_.layout.missing == MissingValues::kSplitRun;
    const bool run_starts = !started_ || keys.run != current_run_ || split;
    const RowZone zone = parted ? zone_of_last_row() : RowZone::kOwned;
    if (zone == RowZone::kAfter) {
      // Past the part: rows of its last run only, as many as asked for.
      if (run_starts || after_rows_ == request_.part.after) {
        part_done_ = true;
        break;
      }
      ++after_rows_;
    }
    if (dropped_ && keys.run == current_run_) ++(split ? missing_.splits : missing_.joins);
    joined_ = dropped_;
    dropped_ = false;
    if (run_starts) {
      started_ = true;
      current_run_ = keys.run;
      has_previous_time_ = false;
      run_span_ = 0;
      run_steps_ = 0;
    }
    if (map_.time >= 0 && !request_.dt) check_time(keys.t, zone == RowZone::kOwned);
    if (block.rows > 0 && (run_starts || zone != block.zone)) {
      // The row begins the next block: a block never spans two runs or two zones.
      pending_.assign(row, row + width);
      has_pending_ = true;
      pending_run_starts_ = run_starts;
      pending_zone_ = zone;
      break;
    }
    if (block.rows == 0) {
      block.run = current_run_;
      block.run_starts = run_starts;
      block.zone = zone;
    }
    ++block.rows;
  }
  block.values.resize(block.rows * width);
  if (block.zone == RowZone::kOwned) rows_read_ += block.rows;
  return block.rows > 0;
}

std::optional<double> StreamReader::time_step() const {
  if (request_.dt) return request_.dt;
  // The metadata's interval is exact where the time column, checked against it, is rounded.
  if (header_.metadata_dt || steps_ == 0) return header_.metadata_dt;
  return span_ / static_cast<double>(steps_);
}

void StreamReader::non_uniform_step(double t, double step) const {
  const auto [found, expected] = distinguished(step, *step_);
  // The steps of the run before this one, as the interval a user would give.
  const double mean = run_steps_ > 0 ? run_span_ / static_cast<double>(run_steps_) : *step_;
  fail(field_location(map_.time),
       "non-uniform time step: " + found + " after " + expected + " at t = " + shortest_decimal(t) +
           " (the steps before it average " + number(mean) + "): give the sample interval with " +
           UsageError::mention("dt") + " " + number(mean) + " if the samples are equally spaced");
}

// check_time's common case, without its messages: take_rows gives the rows it questions back.
// The steps' sum is the span from the last time to the newest (it is what adding them gives,
// without a rounding per step). Four rows at a time where none of them shows more decimals than
// the times before (the allowance stays) and every step is within it; the others one by one.
MOMENTID_KERNEL std::size_t StreamReader::steady_steps(const double* times, std::size_t count) {
  const double reference = *step_;
  double previous = previous_time_;
  std::size_t r = 0;
  for (;;) {
    // The unit of the times' precision changes only where see() finds more decimals.
    const double fixed = fixed_allowance(reference);
    for (; r + 4 <= count && precision_.sees_nothing_new(times + r); r += 4) {
      const Four t = load_four(times + r);
      const Four before = {previous, t[0], t[1], t[2]};
      const Four step = t - before;
      const auto held = (step > 0) & (TimePrecision::magnitude(step - reference) <=
                                      time_allowance(fixed, t, before));
      if (!(held[0] && held[1] && held[2] && held[3])) break;
      previous = t[3];
    }
    // Up to four rows one by one, as check_time takes them.
    const std::size_t end = std::min(count, r + 4);
    for (; r < end; ++r) {
      const double t = times[r];
      precision_.see(t);
      const double step = t - previous;
      if (!(step > 0) || std::abs(step - reference) > step_allowance(t, previous, reference)) break;
      previous = t;
    }
    if (r < end || r == count) break;
  }
  const double span = previous - previous_time_;
  run_span_ += span;
  run_steps_ += r;
  span_ += span;
  steps_ += r;
  previous_time_ = previous;
  return r;
}

void StreamReader::check_time(double t, bool owned) {
  precision_.see(t);
  if (has_previous_time_) {
    const double step = t - previous_time_;
    if (!(step > 0)) {
      fail(field_location(map_.time), "non-increasing time: t = " + shortest_decimal(t) +
                                          " after t = " + shortest_decimal(previous_time_) +
                                          " (samples must be in increasing time order)");
    }
    if (joined_) {
      // Rows dropped for missing values lie between: the step is not a sample interval.
    } else if (!step_) {
      const std::optional<double> dt = header_.metadata_dt;
      if (dt && std::abs(step - *dt) > step_allowance(t, previous_time_, *dt)) {
        fail(field_location(map_.time), "time step " + distinguished(step, *dt).first +
                                            " of column 't' disagrees with " +
                                            header_.metadata_dt_source);
      }
      step_ = step;
    } else if (std::abs(step - *step_) > step_allowance(t, previous_time_, *step_)) {
      non_uniform_step(t, step);
    }
  }
  if (has_previous_time_ && !joined_) {
    run_span_ += t - previous_time_;
    ++run_steps_;
    if (owned) {
      span_ += t - previous_time_;
      ++steps_;
    }
  }
  joined_ = false;
  previous_time_ = t;
  has_previous_time_ = true;
}

void StreamReader::finish(std::size_t rows) {
  if (rows >= request_.min_rows) return;
  fail(last_row_location(), "the data have " + plural(rows, "row") + "; at least " +
                                std::to_string(request_.min_rows) +
                                (request_.min_rows == 1 ? " is" : " are") + " needed");
}

}  // namespace momentid::data
