#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "momentid/error.hpp"
#include "momentid/moment.hpp"
#include "momentid/types.hpp"

namespace momentid {

// How a product with a held input integrates its state part over an interval.
//  kCubic: by the cubic through the rows n - 1 .. n + 2, exact to O(dt^4) for smooth states;
//  kTrapezoidal: by the trapezoidal rule, whose O(dt^2) error is then corrected from the model
//           (derive.hpp, held_input_corrections), as for the moments without an input.
enum class HeldRule { kCubic, kTrapezoidal };

// Time averages of moments E[x^a ...] from a time series, in one streaming pass, kept per
// contiguous stretch of the record so that their sampling covariance can be estimated from batch
// means. Each moment is computed from precomputed powers of the channels and averaged over the
// intervals between consecutive rows of one run, never across runs (see close_interval).
// Interval n of a run is [row n, row n + 1]. An increment (Moment::increment_of) adds
// g(row n + 1) - g(row n) for interval n, so that its sum over a stretch is g at the stretch's
// last row less g at its first, whatever the sampling.
//
// Lagged moments. A factor at lag l is taken l rows before the row of its interval: the moment
// E[y(t - 3) y(t)] averages y[n - 3] y[n] over the intervals. Every moment is averaged over the
// same intervals, those from row L of each run on, where L is the largest lag: the first L rows
// of a run only supply the lagged values. (Without lags nothing changes.) With a held input,
// the input factors are constant over an interval at every lag, and the state part is integrated
// as it is at lag 0.
//
// Precondition: every moment names channels below states + inputs; the constructor throws
// std::invalid_argument naming the offending factor otherwise.
//
// Shards. The state is a value: a record can be cut into shards, each accumulated anywhere,
// serialised, sent, and merged in record order, and the merged moments are those of one pass
// over the record (up to the order of the floating-point sums) with the same interval count.
// A shard is a contiguous range of rows of the record:
//   - begin it with start_run() if its first row starts a run, else with continue_run() and,
//     with lagged moments, add_history() the L rows before it (all rows of the run before it
//     when there are fewer);
//   - add() its rows, calling start_run() where a new run starts inside it;
//   - if its last run goes on past it, add_lookahead() the next rows of that run: kLookaheadRows
//     of them, or all there are if the run ends sooner;
//   - finish().
// An interval belongs to the shard that holds the row before it (the first interval of a run:
// to the shard that started the run). So every interval of a run is owned by one shard, which
// closes it with the same rows and weights as one pass (the cubic weights need the rows
// n - 1 .. n + 2, and lagged factors the L rows before).
//
// Example, one pass:
//   MomentAccumulator acc(moments, /*states=*/2, /*inputs=*/1, InputHold::kZeroOrderHold, 20);
//   acc.start_run();
//   acc.add(rows, n);  // n rows of y1, y2, x
//   acc.finish();
//   MomentEstimates e = estimates(acc, 20);
//
// Example, rows [a, b) of a run on one machine, the rest of the record elsewhere:
//   MomentAccumulator shard(moments, 2, 1, InputHold::kZeroOrderHold, 20);
//   shard.continue_run();
//   shard.add(rows + a * 3, b - a);
//   shard.add_lookahead(rows + b * 3, std::min(run_end - b, MomentAccumulator::kLookaheadRows));
//   shard.finish();
//   send(shard.serialize());
//   ...
//   whole.merge(MomentAccumulator::deserialize(received));  // in record order
class MomentAccumulator {
 public:
  // Rows past its end a shard needs to close its last intervals with the cubic weights.
  static constexpr std::size_t kLookaheadRows = 3;

  // `batches`: how many batches the estimates will be split into at most; the accumulator
  // keeps between 2 and 4 times as many stretches, so its memory does not grow with the record.
  // `rule` matters only with a held input (kSample takes it as kCubic).
  MomentAccumulator(std::vector<Moment> moments, std::size_t states, std::size_t inputs,
                    InputHold hold, std::size_t batches, HeldRule rule = HeldRule::kCubic);

  // The next rows start a new run (a separate record).
  void start_run();
  // The next rows continue a run whose earlier rows went to another shard: the interval from
  // the first of them to the second belongs to that shard.
  void continue_run();
  // After continue_run(): the rows of the run just before the shard, at most the largest lag,
  // used only for the lagged factors of the shard's intervals (std::invalid_argument
  // otherwise).
  void add_history(const double* rows, std::size_t count);
  // Adds `count` consecutive rows of the current run, each states then inputs. Throws
  // std::logic_error after add_lookahead() until the next start_run(), continue_run() or
  // finish().
  void add(const double* rows, std::size_t count);
  // Adds rows just past the end of the shard, of the same run, used only to close the intervals
  // the shard owns. At most kLookaheadRows in all (std::invalid_argument otherwise).
  void add_lookahead(const double* rows, std::size_t count);
  // Closes the current run (or the shard): call after the last rows, before reading the
  // stretches, serialising or merging.
  void finish();
  // Adds the stretches of a finished accumulator into one: for a shard among so many that the
  // batches of the record are made of whole shards. Throws Error in the middle of a run.
  void collapse();
  // Appends the stretches of `other` (finished, the shard after this one's rows) after this
  // one's, closing this one's current run first. Throws Error if `other` is in the middle of a
  // run or if its moments, hold or channel counts differ. The second form takes the stretches
  // over rather than copying them.
  void merge(const MomentAccumulator& other);
  void merge(MomentAccumulator&& other);

  // The state of a finished accumulator as bytes, for deserialize() (throws Error in the middle
  // of a run). Layout version 2, integers and IEEE-754 doubles little-endian:
  //   "MOMACCUM", u32 version, u64 states, u64 inputs, u8 hold (0 sample, 1 zero-order hold,
  //   2 zero-order hold with the trapezoidal rule), u64 batches, u64 moments, per moment {u8 kind
  //   (0 a moment, 1 an increment), u64 factors, per factor {i32 channel, i32 power, i32 lag}},
  //   u64 stretch length, u64 intervals, u64 stretches, per stretch {u64 intervals, f64 sum per
  //   moment}.
  std::vector<std::uint8_t> serialize() const;
  // The accumulator that serialize() wrote into `bytes`. Throws Error saying what was found and
  // what was expected for bytes that are not that: a wrong tag or version, truncated or trailing
  // bytes, counts that do not add up, a moment out of normal form or beyond the limits of a
  // plausible state (4096 channels, power 1024).
  static MomentAccumulator deserialize(std::span<const std::uint8_t> bytes);

  std::size_t intervals() const { return intervals_; }
  // The largest lag of the moments, in rows.
  std::size_t max_lag() const { return max_lag_; }
  const std::vector<Moment>& moments() const { return moments_; }

  // A stretch of the record: the sums of its interval averages (a view of the accumulator's
  // memory, valid until the accumulator changes) and the number of its intervals.
  struct Stretch {
    std::span<const double> sums;
    std::size_t intervals = 0;
  };
  // The stretches so far, in record order, of equal length but the last (unless merged).
  std::vector<Stretch> stretches() const;

 private:
  // The stretches in record order, the open one last. Their sums live in slots of `width`
  // doubles carved from blocks that grow geometrically, a block of 2 MiB or more asked to be
  // backed by large pages: a long pass keeps 2 to 4 times as many stretches as batches,
  // megabytes of sums that would otherwise fault in a page at a time. Compacting and merging
  // hand slots over rather than copy their sums (stretches.cpp).
  class Stretches {
   public:
    explicit Stretches(std::size_t width) : width_(width) {}
    Stretches(const Stretches& other);  // copies the stretches' sums into slots of its own
    Stretches& operator=(const Stretches& other);
    Stretches(Stretches&&) noexcept = default;
    Stretches& operator=(Stretches&&) noexcept = default;
    ~Stretches() = default;

    std::size_t size() const { return slots_.size(); }
    double* sums(std::size_t s) { return slots_[s].sums; }
    const double* sums(std::size_t s) const { return slots_[s].sums; }
    std::size_t& intervals(std::size_t s) { return slots_[s].intervals; }
    std::size_t intervals(std::size_t s) const { return slots_[s].intervals; }
    // Appends a stretch of `intervals` with a copy of `sums` (zeros when null).
    void append(const double* sums, std::size_t intervals);
    // Adds the sums and intervals of stretch `from` to those of stretch `into`.
    void add(std::size_t into, std::size_t from);
    void swap(std::size_t a, std::size_t b) { std::swap(slots_[a], slots_[b]); }
    // Keeps the first `count` stretches; the others' slots serve the stretches to come.
    void truncate(std::size_t count);
    // Appends the stretches of `other` that hold intervals, taking over its memory.
    void take(Stretches&& other);

   private:
    struct Slot {
      double* sums;
      std::size_t intervals;
    };
    struct Free {
      void operator()(double* block) const noexcept;
    };
    double* spare_slot();  // a slot of no stretch, from a new block if none is left

    std::size_t width_;
    std::vector<Slot> slots_;
    std::vector<double*> spare_;
    std::vector<std::unique_ptr<double[], Free>> blocks_;
    std::size_t capacity_ = 0;  // slots in the blocks
  };

  // Laying out the work, before the first row (accumulator_layout.cpp).
  struct Layout;
  void size_history();
  std::vector<Layout> layouts() const;
  void lay_out();
  void group_blocks(const std::vector<Layout>& layouts);
  void choose_singles();
  // The per-row work (accumulator_rows.cpp).
  void store_powers(const double* row);
  void push_rows(const double* rows, std::size_t count);
  void push_row(const double* row);
  bool owns(std::size_t n) const;
  static std::array<double, 4> held_weights(std::size_t n, std::size_t rows, bool cubic);
  void close_interval(std::size_t n);
  void close_stretch();
  void add_plain_products(const double* history);
  void plain_products(double* out, const double* history) const;
  void add_plain(const std::vector<double>& row, double weight);
  // The work of the chunked accumulator, a chunk of rows at a time (accumulator_chunks.cpp).
  void lay_out_chunks(const std::vector<Layout>& layouts);
  void push_chunks(const double* rows, std::size_t count);
  void form_chunk(const double* rows, std::size_t count);
  void close_chunked(std::size_t first, std::size_t last);
  void sum_intervals(std::size_t first, std::size_t last);
  // Runs and stretches (accumulator.cpp).
  void finish_run();
  void open_stretch();  // appends an empty stretch
  void compact();
  void flush();

  std::vector<Moment> moments_;
  std::size_t states_, inputs_;
  InputHold hold_;
  HeldRule rule_;
  std::size_t batches_;
  // Blocks of moments (in working order, positions begin .. begin + size) whose m-th member's
  // factor f reads the history at offset + step * m rows past the newest: each a product of
  // contiguous rows. The state factors come first.
  struct BlockFactor {
    std::size_t offset;  // power-table index * 2 (max_lag_ + 1) + lag of the first member
    int step;            // -1, 0 or 1
  };
  struct Block {
    std::size_t begin, size, state_factors;
    std::vector<BlockFactor> factors;
  };
  std::vector<Block> blocks_;
  // The blocks of one moment with one to four factors (every moment without lags), flat for the
  // per-row loops: the moment's working position, its state factors (held moments) and the
  // history offsets of its factors. The other blocks, by index in blocks_. The held ones are all
  // those kept in the rings, increments included.
  struct Single {
    std::uint32_t position, state_factors, factors;
    std::array<std::uint32_t, 4> offsets;
  };
  std::vector<Single> held_singles_, plain_singles_;
  std::vector<std::size_t> held_blocks_, plain_blocks_;
  // When every moment has at most kChunkFactors factors (every moment of the zero-lag and the
  // lagged equations) and the largest lag is under half a chunk, the moments are formed kChunk rows
  // at a time, column by column, in `chunk_`: stride_ values per column, the pad_ rows before the
  // chunk first (the largest lag and the cubic weights' rows). Its columns: every power of every
  // channel (power 0 a column of ones), then the products of two to four powers, each at its lag,
  // that some moment needs (`products_`, each once, its factors' lags less the smallest). A
  // moment's `whole_` part is its product (for a held moment its state part), `held_input_` the
  // input part of the held ones (positions below increments_begin_): each a column read `lag`
  // rows back, kept as the index in chunk_ of the value for the run's interval 0 (the row max_lag_
  // into the run) less chunk_base_. The intervals
  // whose rows the chunk holds are then closed together, moment by moment along the rows
  // (sum_intervals), without the blocks, rings and per-row sums of the other moments.
  // `chunk_base_`: the run's row (of those this accumulator saw) at the chunk's first;
  // `next_close_`: the first interval of the run not closed.
  static constexpr std::size_t kChunk = 128, kChunkFactors = 4;
  struct ChunkProduct {
    std::uint32_t column, count;
    std::array<std::uint32_t, kChunkFactors> factors;  // columns of powers
    std::array<std::uint32_t, kChunkFactors> lags;
  };
  bool chunked_ = false;
  std::size_t pad_ = 0, stride_ = 0;
  std::vector<double> chunk_;
  std::vector<ChunkProduct> products_;
  std::vector<std::ptrdiff_t> whole_, held_input_;
  std::size_t chunk_base_ = 0, chunk_rows_ = 0, next_close_ = 0;
  // The product of factors [first, last) (1 without any) of a single.
  static double single_product(const Single& one, const double* history, std::uint32_t first,
                               std::uint32_t last);
  static void product(double* out, const Block& b, const double* history, std::size_t first,
                      std::size_t last);

  // Working position -> moment: the held ones first, then the increments, then the others.
  std::vector<std::size_t> order_;
  // Moments kept in the rings: those averaged with a held input, then from increments_begin_
  // the increments (Moment::increment_of).
  std::size_t ringed_count_ = 0, increments_begin_ = 0;
  std::size_t max_lag_ = 0;
  std::vector<int> max_power_;
  std::vector<std::size_t> power_offset_;
  // Per power-table index, its values over the last max_lag_ + 2 rows twice over, the newest at
  // history_pos_.
  std::vector<double> history_;
  std::size_t history_pos_ = 0;
  // At the last four rows of the run (row mod 4), in working order: the state part and the
  // input part of the held moments. The products of the other moments at the newest row and
  // the one before, computed only where needed (and as scratch). The sums of the open stretch.
  std::vector<double> state_ring_, input_ring_, row_, previous_row_, open_sums_;
  // The plain sums (of the moments without a held input) hold an interval whose successor may
  // follow: the last row added has weight 1 in them, and 1/2 if the run or the shard's
  // intervals end there (see push_row).
  bool plain_open_ = false;
  // Rows of the current run this accumulator saw (history and lookahead included), and those of
  // them past the first max_lag_, which have their moments' values in the rings.
  std::size_t seen_rows_ = 0, run_rows_ = 0;
  bool continued_ = false;  // the current run began before this shard (continue_run())
  std::size_t history_rows_ = 0, owned_rows_ = 0, lookahead_rows_ = 0;
  Stretches stretches_;
  std::size_t max_stretches_;
  std::size_t stretch_length_ = 1;  // intervals per stretch, doubled when there are too many
  std::size_t intervals_ = 0;
};

// Moment estimates with the means over contiguous batches of the record, from which their
// sampling covariance is estimated (solve/long_run.hpp).
struct MomentEstimates {
  std::vector<double> mean;                      // one per moment: the time average
  std::vector<std::vector<double>> batch_means;  // batches x moments
  // Per batch, its intervals: batches differ in length by up to one stretch. Empty: all alike.
  std::vector<std::size_t> batch_intervals;
  std::size_t intervals = 0;
};

// Groups the accumulator's stretches into `batches` contiguous batches (fewer if the record is
// short) and returns the overall means and the batch means.
MomentEstimates estimates(const MomentAccumulator& accumulator, std::size_t batches);

}  // namespace momentid
