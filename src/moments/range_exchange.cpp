// The ranges of a pass that other processes read (an MPI job): each range's result as bytes,
// errors included, and the ranges merged in rank order.

#include <string>
#include <string_view>

#include "common/bytes.hpp"
#include "moments/range.hpp"

namespace momentid {
namespace {

// Strings in the result of another process: a length, then the bytes.
void put_text(ByteWriter& out, std::string_view text) {
  out.u64(text.size());
  out.bytes(text.data(), text.size());
}

std::string get_text(ByteReader& in) {
  const auto bytes = in.take(in.count(1, "characters"), "a text");
  return {bytes.begin(), bytes.end()};
}

void write_optional(ByteWriter& out, const std::optional<double>& v) {
  out.u64(v ? 1 : 0);
  out.f64(v.value_or(0));
}

std::optional<double> read_optional(ByteReader& in) {
  const bool has = in.u64("whether a value is there") != 0;
  const double v = in.f64("a value");
  return has ? std::optional(v) : std::nullopt;
}

void write_location(ByteWriter& out, const SourceLocation& at) {
  put_text(out, at.file);
  out.i32(at.line);
  out.i32(at.column);
  put_text(out, at.text);
}

SourceLocation read_location(ByteReader& in) {
  SourceLocation at;
  at.file = get_text(in);
  at.line = in.i32("a line");
  at.column = in.i32("a column");
  at.text = get_text(in);
  return at;
}

// An error as another process rethrows it: its kind, place and message.
enum class ErrorKind : std::uint64_t { kData = 1, kUsage, kOther };

void write_error(ByteWriter& out, const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const DataError& e) {
    out.u64(static_cast<std::uint64_t>(ErrorKind::kData));
    write_location(out, e.location());
    put_text(out, e.message());
  } catch (const UsageError& e) {
    out.u64(static_cast<std::uint64_t>(ErrorKind::kUsage));
    put_text(out, e.what());
  } catch (const std::exception& e) {
    out.u64(static_cast<std::uint64_t>(ErrorKind::kOther));
    put_text(out, e.what());
  }
}

std::exception_ptr read_error(ByteReader& in) {
  switch (static_cast<ErrorKind>(in.u64("the kind of an error"))) {
    case ErrorKind::kData: {
      SourceLocation at = read_location(in);
      return std::make_exception_ptr(DataError(std::move(at), get_text(in)));
    }
    case ErrorKind::kUsage:
      return std::make_exception_ptr(UsageError(get_text(in)));
    default:
      return std::make_exception_ptr(Error(get_text(in)));
  }
}

}  // namespace

std::vector<std::uint8_t> encode(const RangeResult& r) {
  ByteWriter out;
  const std::vector<std::uint8_t> moments = r.state->moments.serialize();
  out.u64(moments.size());
  out.bytes(reinterpret_cast<const char*>(moments.data()), moments.size());
  r.state->lags.save(out);
  out.u64(r.state->rows);
  out.u64(r.state->runs);
  out.u64(r.summaries.size());
  for (const ShardSummary& s : r.summaries) {
    out.u64(s.steps.count);
    out.f64(s.steps.sum);
    write_optional(out, s.time_step);
    out.u64(s.missing.rows);
    out.u64(s.missing.splits);
    out.u64(s.missing.joins);
    out.u64(s.missing.first ? 1 : 0);
    if (s.missing.first) write_location(out, *s.missing.first);
  }
  out.u64(r.error ? r.first_error : std::numeric_limits<std::uint64_t>::max());
  if (r.error) write_error(out, r.error);
  return out.take();
}

RangeResult decode(const std::vector<std::uint8_t>& bytes, std::size_t channels, std::size_t lags) {
  ByteReader in(bytes, "the bytes of another process");
  RangeResult r;
  MomentAccumulator moments =
      MomentAccumulator::deserialize(in.take(in.count(1, "accumulator bytes"), "its state"));
  LagSums sums = LagSums::load(in, channels, lags);
  r.state.emplace(ShardState{std::move(moments), std::move(sums)});
  r.state->rows = in.u64("the row count");
  r.state->runs = in.u64("the run count");
  r.summaries.resize(in.count(8, "shard summaries"));
  for (ShardSummary& s : r.summaries) {
    s.steps.count = in.u64("a step count");
    s.steps.sum = in.f64("a sum of steps");
    s.time_step = read_optional(in);
    s.missing.rows = in.u64("a count of missing rows");
    s.missing.splits = in.u64("a count of splits");
    s.missing.joins = in.u64("a count of joins");
    if (in.u64("whether a missing row is located") != 0) s.missing.first = read_location(in);
  }
  const std::uint64_t first_error = in.u64("the first failed shard");
  if (first_error != std::numeric_limits<std::uint64_t>::max()) {
    r.first_error = static_cast<std::size_t>(first_error);
    r.error = read_error(in);
  }
  return r;
}

RangeResult merge_ranges(std::vector<RangeResult> ranges) {
  RangeResult out = std::move(ranges.front());
  for (std::size_t r = 1; r < ranges.size(); ++r) {
    RangeResult& next = ranges[r];
    if (out.error) break;
    out.state->moments.merge(std::move(next.state->moments));
    out.state->lags.merge(next.state->lags);
    out.state->rows += next.state->rows;
    out.state->runs += next.state->runs;
    for (ShardSummary& s : next.summaries) out.summaries.push_back(std::move(s));
    out.first_error = next.first_error;
    out.error = next.error;
  }
  return out;
}

}  // namespace momentid
