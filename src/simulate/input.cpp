#include "momentid/input.hpp"

#include <charconv>
#include <cmath>
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

}  // namespace

InputSpec InputSpec::parse(const std::string& text, const std::string& option) {
  InputSpec spec;
  const std::size_t colon = text.find(':');
  const std::string kind = text.substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : text.substr(colon + 1);
  if (kind == "ma") {
    spec.kind = Kind::kMovingAverage;
  } else if (kind == "ou") {
    spec.kind = Kind::kOrnsteinUhlenbeck;
  } else if (kind == "white") {
    spec.kind = Kind::kWhite;
  } else {
    throw UsageError(option + ": unknown input process '" + kind +
                     "' (expected ma:K=10,w=0.1, ou:tau=T or white)");
  }
  double equal_weight = 0.1;
  long count = 10;
  bool explicit_weights = false, has_count = false, has_w = false, has_tau = false;
  if (!rest.empty()) {
    for (const std::string& item : split_items(rest)) {
      const std::size_t eq = item.find('=');
      if (eq == std::string::npos) {
        throw UsageError(option + ": expected key=value, found '" + item + "'");
      }
      const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
      const bool ma = spec.kind == Kind::kMovingAverage;
      if (key == "sigma") {
        spec.sigma = parse_number(value, "sigma", option);
        if (spec.sigma < 0) throw UsageError(option + ": sigma must not be negative");
      } else if (key == "mean") {
        spec.mean = parse_number(value, "mean", option);
      } else if (ma && key == "K") {
        const double k = parse_number(value, "K", option);
        if (k < 1 || k > 1000000 || k != std::floor(k)) {
          throw UsageError(option + ": K must be a whole number from 1 to 1000000, found '" +
                           value + "'");
        }
        count = static_cast<long>(k);
        has_count = true;
      } else if (ma && key == "w") {
        equal_weight = parse_number(value, "w", option);
        has_w = true;
      } else if (ma && key == "weights") {
        if (value.size() < 2 || value.front() != '[' || value.back() != ']') {
          throw UsageError(option + ": weights must be a list such as [0.3,0.4,0.3], found '" +
                           value + "'");
        }
        spec.weights.clear();
        for (const std::string& w : split_items(value.substr(1, value.size() - 2))) {
          spec.weights.push_back(parse_number(w, "a weight", option));
        }
        explicit_weights = true;
      } else if (spec.kind == Kind::kOrnsteinUhlenbeck && key == "tau") {
        spec.tau = parse_number(value, "tau", option);
        if (spec.tau <= 0) throw UsageError(option + ": tau must be positive");
        has_tau = true;
      } else {
        throw UsageError(option + ": unknown setting '" + key + "' for a " + kind + " input");
      }
    }
  }
  if (spec.kind == Kind::kMovingAverage) {
    if (explicit_weights && (has_count || has_w)) {
      throw UsageError(option + ": give either K and w, or weights, not both");
    }
    if (!explicit_weights) spec.weights.assign(static_cast<std::size_t>(count), equal_weight);
  }
  if (spec.kind == Kind::kOrnsteinUhlenbeck && !has_tau) {
    throw UsageError(option + ": an ou input needs its correlation time, e.g. ou:tau=0.5");
  }
  return spec;
}

std::string InputSpec::text() const {
  std::string out;
  switch (kind) {
    case Kind::kMovingAverage: {
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
  }
  if (out.back() != ':') out += ",";
  return out + "sigma=" + shortest_decimal(sigma) + ",mean=" + shortest_decimal(mean);
}

InputProcess::InputProcess(const InputSpec& spec, double dt, std::uint64_t seed,
                           std::uint64_t stream)
    : spec_(spec), random_(seed, stream) {
  switch (spec_.kind) {
    case InputSpec::Kind::kMovingAverage:
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
  }
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
  }
  return 0;
}

}  // namespace momentid
