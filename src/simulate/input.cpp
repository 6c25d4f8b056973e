#include "momentid/input.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>

#include "common/decimal.hpp"
#include "momentid/error.hpp"

namespace momentid {
namespace {

double parse_number(const std::string& text, const std::string& what, const std::string& option) {
  double value = 0;
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, value);
  if (text.empty() || result.ec != std::errc() || result.ptr != end || !std::isfinite(value)) {
    throw UsageError(option + ": " + what + " must be a number, found '" + text + "'");
  }
  return value;
}

// Splits "a=1,b=[2,3],c" at the commas that are not inside brackets.
std::vector<std::string> split_items(const std::string& text) {
  std::vector<std::string> out;
  std::string current;
  int depth = 0;
  for (char ch : text) {
    if (ch == '[') ++depth;
    if (ch == ']') --depth;
    if (ch == ',' && depth == 0) {
      out.push_back(current);
      current.clear();
    } else {
      current += ch;
    }
  }
  out.push_back(current);
  return out;
}

// The smallest m >= 0 that puts the lowest of `lines` odd harmonics of f0 = f2 / (2m + 2 lines - 1)
// at or above f1, or nothing when m would exceed kMaxOffset (a band too narrow for the lines).
constexpr double kMaxOffset = 1e9;
std::optional<std::uint64_t> lowest_harmonic_offset(double f1, double f2, std::uint32_t lines) {
  const double top = 2.0 * lines - 1;
  const auto reaches = [&](double m) { return (2 * m + 1) * f2 >= f1 * (2 * m + top); };
  // (2m + 1) f2 >= f1 (2m + 2L - 1)  <=>  m >= (f1 (2L - 1) - f2) / (2 (f2 - f1)).
  const double estimate = std::ceil((f1 * top - f2) / (2 * (f2 - f1)));
  if (!(estimate <= kMaxOffset)) return std::nullopt;
  double m = std::max(0.0, estimate);
  while (m > 0 && reaches(m - 1)) --m;
  while (!reaches(m)) {
    if (++m > kMaxOffset) return std::nullopt;
  }
  return static_cast<std::uint64_t>(m);
}

// The checks that do not depend on the step; the messages are those of parse().
void check_values(const InputSpec& spec, const std::string& option) {
  if (!(std::isfinite(spec.mean))) throw UsageError(option + ": mean must be a finite number");
  switch (spec.kind) {
    case InputSpec::Kind::kMovingAverage:
    case InputSpec::Kind::kOrnsteinUhlenbeck:
    case InputSpec::Kind::kWhite:
      if (!(spec.sigma >= 0 && std::isfinite(spec.sigma))) {
        throw UsageError(option + ": sigma must not be negative");
      }
      if (spec.kind == InputSpec::Kind::kMovingAverage && spec.window > 0 &&
          !std::isfinite(spec.window)) {
        throw UsageError(option + ": T must be a positive number of seconds");
      }
      if (spec.kind == InputSpec::Kind::kMovingAverage && spec.weights.empty() &&
          spec.window == 0) {
        throw UsageError(option + ": a moving average needs at least one weight");
      }
      if (spec.kind == InputSpec::Kind::kOrnsteinUhlenbeck &&
          !(spec.tau > 0 && std::isfinite(spec.tau))) {
        throw UsageError(option + ": tau must be positive");
      }
      return;
    case InputSpec::Kind::kMultisine:
      if (!(spec.f1 > 0 && std::isfinite(spec.f1))) {
        throw UsageError(option + ": f1 must be positive");
      }
      if (!(spec.f2 > 0 && std::isfinite(spec.f2))) {
        throw UsageError(option + ": f2 must be positive");
      }
      if (!(spec.f1 < spec.f2)) {
        throw UsageError(option + ": f1 must be below f2, found f1=" + shortest_decimal(spec.f1) +
                         " and f2=" + shortest_decimal(spec.f2));
      }
      if (spec.lines < 1 || spec.lines > InputSpec::kMaxLines) {
        throw UsageError(option + ": lines must be a whole number from 1 to " +
                         std::to_string(InputSpec::kMaxLines) + ", found '" +
                         std::to_string(spec.lines) + "'");
      }
      if (!(spec.rms > 0 && std::isfinite(spec.rms))) {
        throw UsageError(option + ": rms must be positive");
      }
      if (!lowest_harmonic_offset(spec.f1, spec.f2, spec.lines)) {
        throw UsageError(option + ": the band from f1=" + shortest_decimal(spec.f1) +
                         " to f2=" + shortest_decimal(spec.f2) + " is too narrow for " +
                         std::to_string(spec.lines) + " lines");
      }
      return;
  }
}

bool valid_band(const InputSpec& spec) {
  return spec.kind == InputSpec::Kind::kMultisine && spec.f1 > 0 && spec.f1 < spec.f2 &&
         std::isfinite(spec.f2) && spec.lines >= 1 && spec.lines <= InputSpec::kMaxLines;
}

}  // namespace

namespace {

// What parse() has read of the settings besides the spec: the moving average's K and w, and
// which settings were given.
struct Given {
  double equal_weight = 0.1;
  long count = 10;
  bool weights = false, count_given = false, w = false, window = false, tau = false;
  bool f1 = false, f2 = false, lines = false;
};

// A setting that must be a positive number: "OPTION: KEY must be positive" otherwise.
double positive_number(const std::string& value, const std::string& key,
                       const std::string& option) {
  const double x = parse_number(value, key, option);
  if (x <= 0) throw UsageError(option + ": " + key + " must be positive");
  return x;
}

// One setting of the text form: its key, the processes that take it, and what it sets.
struct Setting {
  const char* key;
  bool (*takes)(InputKind);
  void (*apply)(InputSpec&, Given&, const std::string& value, const std::string& option);
};

bool moving_average(InputKind p) { return p == InputKind::kMovingAverage; }
bool multisine(InputKind p) { return p == InputKind::kMultisine; }
bool ornstein_uhlenbeck(InputKind p) { return p == InputKind::kOrnsteinUhlenbeck; }
bool random(InputKind p) { return p != InputKind::kMultisine; }
bool any(InputKind) { return true; }

const Setting kSettings[] = {
    {"sigma", random,
     [](InputSpec& s, Given&, const std::string& value, const std::string& option) {
       s.sigma = parse_number(value, "sigma", option);
       if (s.sigma < 0) throw UsageError(option + ": sigma must not be negative");
     }},
    {"mean", any,
     [](InputSpec& s, Given&, const std::string& value, const std::string& option) {
       s.mean = parse_number(value, "mean", option);
     }},
    {"K", moving_average,
     [](InputSpec&, Given& g, const std::string& value, const std::string& option) {
       const double k = parse_number(value, "K", option);
       if (k < 1 || k > 1000000 || k != std::floor(k)) {
         throw UsageError(option + ": K must be a whole number from 1 to 1000000, found '" + value +
                          "'");
       }
       g.count = static_cast<long>(k);
       g.count_given = true;
     }},
    {"T", moving_average,
     [](InputSpec& s, Given& g, const std::string& value, const std::string& option) {
       s.window = parse_number(value, "T", option);
       if (!(s.window > 0)) {
         throw UsageError(option + ": T must be a positive number of seconds, found '" + value +
                          "'");
       }
       g.window = true;
     }},
    {"w", moving_average,
     [](InputSpec&, Given& g, const std::string& value, const std::string& option) {
       g.equal_weight = parse_number(value, "w", option);
       g.w = true;
     }},
    {"weights", moving_average,
     [](InputSpec& s, Given& g, const std::string& value, const std::string& option) {
       if (value.size() < 2 || value.front() != '[' || value.back() != ']') {
         throw UsageError(option + ": weights must be a list such as [0.3,0.4,0.3], found '" +
                          value + "'");
       }
       s.weights.clear();
       for (const std::string& w : split_items(value.substr(1, value.size() - 2))) {
         s.weights.push_back(parse_number(w, "a weight", option));
       }
       g.weights = true;
     }},
    {"tau", ornstein_uhlenbeck,
     [](InputSpec& s, Given& g, const std::string& value, const std::string& option) {
       s.tau = positive_number(value, "tau", option);
       g.tau = true;
     }},
    {"f1", multisine,
     [](InputSpec& s, Given& g, const std::string& value, const std::string& option) {
       s.f1 = positive_number(value, "f1", option);
       g.f1 = true;
     }},
    {"f2", multisine,
     [](InputSpec& s, Given& g, const std::string& value, const std::string& option) {
       s.f2 = positive_number(value, "f2", option);
       g.f2 = true;
     }},
    {"lines", multisine,
     [](InputSpec& s, Given& g, const std::string& value, const std::string& option) {
       const double lines = parse_number(value, "lines", option);
       if (lines < 1 || lines > InputSpec::kMaxLines || lines != std::floor(lines)) {
         throw UsageError(option + ": lines must be a whole number from 1 to " +
                          std::to_string(InputSpec::kMaxLines) + ", found '" + value + "'");
       }
       s.lines = static_cast<std::uint32_t>(lines);
       g.lines = true;
     }},
    {"rms", multisine,
     [](InputSpec& s, Given&, const std::string& value, const std::string& option) {
       s.rms = positive_number(value, "rms", option);
     }},
};

// The settings' joint rules: a moving average's window in samples or seconds, not both; the
// settings an ou or multisine input cannot do without.
void complete(InputSpec& spec, const Given& g, const std::string& option) {
  if (spec.kind == InputKind::kMovingAverage) {
    if (g.weights && (g.count_given || g.w)) {
      throw UsageError(option + ": give either K and w, or weights, not both");
    }
    if (g.window && (g.count_given || g.weights)) {
      throw UsageError(option + ": give the window either in seconds (T) or in samples (K or " +
                       "weights), not both");
    }
    if (g.window) {
      spec.weights.clear();
      if (g.w) spec.weights.push_back(g.equal_weight);
    } else if (!g.weights) {
      spec.weights.assign(static_cast<std::size_t>(g.count), g.equal_weight);
    }
  }
  if (spec.kind == InputKind::kOrnsteinUhlenbeck && !g.tau) {
    throw UsageError(option + ": an ou input needs its correlation time, e.g. ou:tau=0.5");
  }
  if (spec.kind == InputKind::kMultisine) {
    if (!g.f1 || !g.f2 || !g.lines) {
      throw UsageError(option +
                       ": a multisine input needs f1, f2 and lines, e.g. "
                       "multisine:f1=0.5,f2=5,lines=10");
    }
    check_values(spec, option);
  }
}

}  // namespace

InputSpec InputSpec::parse(const std::string& text, const std::string& option) {
  InputSpec spec;
  const std::size_t colon = text.find(':');
  const std::string kind = text.substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : text.substr(colon + 1);
  const std::vector<std::string> kinds = names_of<InputKind>();
  if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end()) {
    throw UsageError(option + ": unknown input process '" + kind +
                     "' (expected ma:K=10,w=0.1, ou:tau=T, white or "
                     "multisine:f1=F1,f2=F2,lines=L)");
  }
  spec.kind = parse_input_kind(kind, option);
  Given given;
  for (const std::string& item : rest.empty() ? std::vector<std::string>{} : split_items(rest)) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      throw UsageError(option + ": expected key=value, found '" + item + "'");
    }
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    const auto setting = std::find_if(std::begin(kSettings), std::end(kSettings),
                                      [&](const Setting& s) { return key == s.key; });
    if (setting == std::end(kSettings) || !setting->takes(spec.kind)) {
      throw UsageError(option + ": unknown setting '" + key + "' for a " + kind + " input");
    }
    setting->apply(spec, given, value, option);
  }
  complete(spec, given, option);
  return spec;
}

std::string InputSpec::text() const {
  std::string out;
  switch (kind) {
    case Kind::kMovingAverage: {
      if (window > 0) {
        out = "ma:T=" + shortest_decimal(window);
        if (!weights.empty()) out += ",w=" + shortest_decimal(weights.front());
        break;
      }
      bool equal = true;
      for (double w : weights) equal = equal && w == weights.front();
      if (equal) {
        out = "ma:K=" + std::to_string(weights.size()) + ",w=" + shortest_decimal(weights.front());
      } else {
        out = "ma:weights=[";
        for (std::size_t i = 0; i < weights.size(); ++i) {
          if (i) out += ',';
          out += shortest_decimal(weights[i]);
        }
        out += "]";
      }
      break;
    }
    case Kind::kOrnsteinUhlenbeck:
      out = "ou:tau=" + shortest_decimal(tau);
      break;
    case Kind::kWhite:
      out = "white:";
      break;
    case Kind::kMultisine:
      return "multisine:f1=" + shortest_decimal(f1) + ",f2=" + shortest_decimal(f2) +
             ",lines=" + std::to_string(lines) + ",rms=" + shortest_decimal(rms) +
             ",mean=" + shortest_decimal(mean);
  }
  if (out.back() != ':') out += ",";
  return out + "sigma=" + shortest_decimal(sigma) + ",mean=" + shortest_decimal(mean);
}

std::vector<double> InputSpec::weights_at(double dt) const {
  if (window == 0) return weights;
  const auto k = static_cast<std::size_t>(std::max(1.0, std::round(window / dt)));
  return std::vector<double>(k, weights.empty() ? 1.0 / static_cast<double>(k) : weights.front());
}

void InputSpec::validate(const std::string& option, double dt) const {
  check_values(*this, option);
  if (kind == Kind::kMovingAverage && window > 0 &&
      !(window >= 0.5 * dt && window / dt <= static_cast<double>(kMaxWeights))) {
    throw UsageError(option + ": T=" + shortest_decimal(window) + " is " +
                     (window < 0.5 * dt ? "shorter than half a step"
                                        : "longer than " + std::to_string(kMaxWeights) + " steps") +
                     " (dt = " + shortest_decimal(dt) + ")");
  }
  if (kind == Kind::kMultisine && !(f2 < 0.5 / dt)) {
    throw UsageError(
        option + ": f2=" + shortest_decimal(f2) +
        " must be below the Nyquist frequency 1/(2 dt) = " + shortest_decimal(0.5 / dt));
  }
}

double InputSpec::base_frequency() const {
  const auto m = valid_band(*this) ? lowest_harmonic_offset(f1, f2, lines) : std::nullopt;
  if (!m) return 0;
  return f2 / static_cast<double>(2 * *m + 2 * lines - 1);
}

std::vector<std::uint64_t> InputSpec::harmonics() const {
  const auto m = valid_band(*this) ? lowest_harmonic_offset(f1, f2, lines) : std::nullopt;
  std::vector<std::uint64_t> out;
  if (!m) return out;
  for (std::uint64_t j = 0; j < lines; ++j) out.push_back(2 * *m + 2 * j + 1);
  return out;
}

InputProcess::InputProcess(const InputSpec& spec, double dt, std::uint64_t seed,
                           std::uint64_t stream)
    : spec_(spec), random_(seed, stream) {
  switch (spec_.kind) {
    case InputSpec::Kind::kMovingAverage:
      spec_.weights = spec.weights_at(dt);
      spec_.window = 0;
      // The filter starts full, so the first output is already stationary.
      history_.resize(spec_.weights.size());
      for (double& v : history_) v = spec_.mean + spec_.sigma * random_.normal();
      break;
    case InputSpec::Kind::kOrnsteinUhlenbeck:
      decay_ = portable_exp(-dt / spec_.tau);
      innovation_ = std::sqrt(1 - decay_ * decay_);
      state_ = spec_.sigma * random_.normal();
      break;
    case InputSpec::Kind::kWhite:
      break;
    case InputSpec::Kind::kMultisine: {
      const double half_step = spec_.base_frequency() * (dt / 2);
      for (std::uint64_t n : spec_.harmonics()) {
        cycles_per_half_step_.push_back(static_cast<double>(n) * half_step);
      }
      amplitude_ = spec_.rms * std::sqrt(2.0 / static_cast<double>(spec_.lines));
      draw_phases();
      break;
    }
  }
}

void InputProcess::draw_phases() {
  phases_.clear();
  for (std::size_t j = 0; j < cycles_per_half_step_.size(); ++j) {
    phases_.push_back(random_.uniform());
  }
}

void InputProcess::start_record(std::size_t burn_in) {
  if (spec_.kind != InputSpec::Kind::kMultisine) return;
  if (records_started_) draw_phases();
  records_started_ = true;
  end_clock_ = -1;
  clock_ = -2 * static_cast<std::int64_t>(burn_in);
}

double InputProcess::multisine_at(std::int64_t half_steps) const {
  const double k = static_cast<double>(half_steps);
  double sum = 0;
  for (std::size_t j = 0; j < phases_.size(); ++j) {
    sum += portable_cos_turns(cycles_per_half_step_[j] * k + phases_[j]);
  }
  return spec_.mean + amplitude_ * sum;
}

double InputProcess::next() {
  switch (spec_.kind) {
    case InputSpec::Kind::kMovingAverage: {
      head_ = head_ == 0 ? history_.size() - 1 : head_ - 1;
      history_[head_] = spec_.mean + spec_.sigma * random_.normal();
      // weights[i] multiplies v_{n-i}, which sits at history_[(head_ + i) mod K].
      const std::size_t k = history_.size();
      const std::size_t wrap = k - head_;
      double sum = 0;
      for (std::size_t i = 0; i < wrap; ++i) sum += spec_.weights[i] * history_[head_ + i];
      for (std::size_t i = wrap; i < k; ++i) sum += spec_.weights[i] * history_[i - wrap];
      return sum;
    }
    case InputSpec::Kind::kOrnsteinUhlenbeck: {
      const double value = spec_.mean + state_;
      state_ = decay_ * state_ + innovation_ * spec_.sigma * random_.normal();
      return value;
    }
    case InputSpec::Kind::kWhite:
      return spec_.mean + spec_.sigma * random_.normal();
    case InputSpec::Kind::kMultisine: {
      // The end of one step is the start of the next: same clock, same value.
      const double start = end_clock_ == clock_ ? end_ : multisine_at(clock_);
      middle_ = multisine_at(clock_ + 1);
      end_ = multisine_at(clock_ + 2);
      clock_ += 2;
      end_clock_ = clock_;
      return start;
    }
  }
  return 0;
}

}  // namespace momentid
