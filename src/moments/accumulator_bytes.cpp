// A MomentAccumulator's state as bytes (layout version 2, see MomentAccumulator::serialize), and
// back, checking every count and value it reads.

#include <algorithm>
#include <bit>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "common/bytes.hpp"
#include "data/text.hpp"
#include "momentid/accumulator.hpp"

namespace momentid {
namespace {

constexpr char kTag[8] = {'M', 'O', 'M', 'A', 'C', 'C', 'U', 'M'};
constexpr std::uint32_t kLayoutVersion = 2;
// Bounds on what deserialize() accepts, so that corrupt counts cannot ask for huge tables.
constexpr std::uint64_t kMaxChannels = 4096;
constexpr int kMaxPower = 1024;

std::string hex(std::span<const std::uint8_t> bytes) {
  static const char digits[] = "0123456789abcdef";
  std::string out;
  for (std::uint8_t b : bytes) {
    if (!out.empty()) out += ' ';
    out += digits[b >> 4];
    out += digits[b & 15];
  }
  return out;
}

// What the layout says before the moments.
struct Header {
  std::uint64_t states = 0, inputs = 0, batches = 0;
  std::uint8_t hold = 0;
};

Header read_header(ByteReader& in) {
  const auto tag = in.take(sizeof kTag, "the tag");
  if (!std::equal(tag.begin(), tag.end(), kTag)) {
    throw Error("not moment accumulator bytes: they start with " + hex(tag) +
                ", expected the tag \"MOMACCUM\"");
  }
  const std::uint32_t version = in.u32("the layout version");
  if (version != kLayoutVersion) {
    throw Error("moment accumulator bytes of layout version " + std::to_string(version) +
                ", expected version " + std::to_string(kLayoutVersion));
  }
  Header h;
  h.states = in.u64("the number of states");
  h.inputs = in.u64("the number of inputs");
  if (h.states > kMaxChannels || h.inputs > kMaxChannels - h.states) {
    throw Error("moment accumulator bytes: " + std::to_string(h.states) + " states and " +
                std::to_string(h.inputs) + " inputs, expected at most " +
                std::to_string(kMaxChannels) + " channels");
  }
  h.hold = in.u8("the input hold");
  if (h.hold > 2) {
    throw Error("moment accumulator bytes: input hold " + std::to_string(h.hold) +
                ", expected 0 (sample), 1 (zero-order hold) or 2 (zero-order hold, trapezoidal)");
  }
  h.batches = in.u64("the number of batches");
  if (h.batches > std::numeric_limits<std::size_t>::max() / 4) {
    throw Error("moment accumulator bytes: " + std::to_string(h.batches) +
                " batches, expected at most " +
                std::to_string(std::numeric_limits<std::size_t>::max() / 4));
  }
  return h;
}

// Moment `name` over `channels` channels, in normal form.
Moment read_moment(ByteReader& in, const std::string& name, std::size_t channels) {
  const std::uint8_t kind = in.u8("the kind of " + name);
  if (kind > 1) {
    throw Error("moment accumulator bytes: " + name + " of kind " + std::to_string(kind) +
                ", expected 0 (a moment) or 1 (an increment)");
  }
  std::vector<MomentFactor> factors(in.count(12, "factors of " + name));
  for (MomentFactor& f : factors) {
    f.channel = in.i32("a factor of " + name);
    f.power = in.i32("a factor of " + name);
    f.lag = in.i32("a factor of " + name);
    if (f.power < 1 || f.power > kMaxPower || f.channel < 0 || f.lag < 0) {
      throw Error("moment accumulator bytes: " + name + " has the factor channel " +
                  std::to_string(f.channel) + ", power " + std::to_string(f.power) + ", lag " +
                  std::to_string(f.lag) +
                  ", expected a channel and lag from 0 and a power from 1 to " +
                  std::to_string(kMaxPower));
    }
  }
  Moment m(factors);
  if (kind == 1) {
    if (m.is_lagged()) {
      throw Error("moment accumulator bytes: " + name +
                  " is an increment with lagged factors, expected every factor at lag 0");
    }
    m = Moment::increment_of(m.at_lag(0, channels));
  }
  if (m.factors() != factors) {
    throw Error("moment accumulator bytes: the factors of " + name +
                " are not in normal form (expected " + to_string(m) + ")");
  }
  return m;
}

}  // namespace

std::vector<std::uint8_t> MomentAccumulator::serialize() const {
  if (seen_rows_ > 0) {
    throw Error(
        "cannot serialise a moment accumulator in the middle of a run: call finish() first");
  }
  ByteWriter out;
  out.bytes(kTag, sizeof kTag);
  out.u32(kLayoutVersion);
  out.u64(states_);
  out.u64(inputs_);
  out.u8(hold_ == InputHold::kSample ? 0 : rule_ == HeldRule::kCubic ? 1 : 2);
  out.u64(batches_);
  out.u64(moments_.size());
  for (const Moment& m : moments_) {
    out.u8(m.is_increment() ? 1 : 0);
    out.u64(m.factors().size());
    for (const MomentFactor& f : m.factors()) {
      out.i32(f.channel);
      out.i32(f.power);
      out.i32(f.lag);
    }
  }
  out.u64(stretch_length_);
  out.u64(intervals_);
  out.u64(stretches_.size());
  for (std::size_t s = 0; s < stretches_.size(); ++s) {
    out.u64(stretches_.intervals(s));
    for (std::size_t j = 0; j < moments_.size(); ++j) out.f64(stretches_.sums(s)[j]);
  }
  return out.take();
}

MomentAccumulator MomentAccumulator::deserialize(std::span<const std::uint8_t> bytes) {
  ByteReader in(bytes, "moment accumulator bytes");
  const Header h = read_header(in);
  std::optional<MomentAccumulator> out;
  try {
    std::vector<Moment> moments(in.count(4, "moments"));
    for (std::size_t i = 0; i < moments.size(); ++i) {
      moments[i] = read_moment(in, "moment " + std::to_string(i), h.states + h.inputs);
    }
    out.emplace(std::move(moments), h.states, h.inputs,
                h.hold == 0 ? InputHold::kSample : InputHold::kZeroOrderHold, h.batches,
                h.hold == 2 ? HeldRule::kTrapezoidal : HeldRule::kCubic);
  } catch (const std::invalid_argument& e) {
    throw Error(std::string("moment accumulator bytes: ") + e.what());
  }
  const std::uint64_t length = in.u64("the stretch length");
  if (!std::has_single_bit(length)) {
    throw Error("moment accumulator bytes: stretch length " + std::to_string(length) +
                ", expected a power of two");
  }
  const std::uint64_t intervals = in.u64("the number of intervals");
  // The stretches, which must hold `intervals` intervals in all.
  const std::size_t stretches = in.count(8 * (out->moments_.size() + 1), "stretches");
  if (stretches == 0) {
    throw Error("moment accumulator bytes: no stretches, expected at least the open one");
  }
  out->stretches_.truncate(0);
  std::vector<double> sums(out->moments_.size());
  std::uint64_t counted = 0;
  for (std::size_t s = 0; s < stretches; ++s) {
    const std::uint64_t count = in.u64("the interval count of a stretch");
    for (double& x : sums) x = in.f64("a sum of a stretch");
    if (count > intervals - counted) {
      throw Error("moment accumulator bytes: the stretches hold more than the " +
                  std::to_string(intervals) + " intervals counted");
    }
    counted += count;
    out->stretches_.append(sums.data(), count);
  }
  if (counted != intervals) {
    throw Error("moment accumulator bytes: " + std::to_string(intervals) +
                " intervals counted, but the stretches hold " + std::to_string(counted));
  }
  if (in.position() != bytes.size()) {
    throw Error("moment accumulator bytes: " + data::plural(bytes.size() - in.position(), "byte") +
                " after the end of the layout at byte " + std::to_string(in.position()));
  }
  out->stretch_length_ = length;
  out->intervals_ = intervals;
  return std::move(*out);
}

}  // namespace momentid
