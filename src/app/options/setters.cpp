#include "app/options/setters.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>

#include "momentid/error.hpp"
#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "momentid/types.hpp"

namespace momentid {
namespace {

// The whole of `text` as T, by std::from_chars.
template <class T>
bool read_exactly(const std::string& text, T& value) {
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value);
  return !text.empty() && error == std::errc() && stop == end;
}

}  // namespace

double parse_option_number(const std::string& text, const std::string& name) {
  // As CLI11 reads a double: through the nearest long double.
  char* end = nullptr;
  const long double value = std::strtold(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) {
    throw UsageError(name, "expected a number, found '" + text + "'");
  }
  return static_cast<double>(value);
}

std::string option_number_text(double value) {
  char text[64];
  const auto shortest = std::to_chars(text, text + sizeof text, value);
  const std::string out(text, shortest.ptr);
  if (static_cast<double>(std::strtold(out.c_str(), nullptr)) == value) return out;
  // Seventeen digits read back through a long double as the same double, always.
  const auto exact = std::to_chars(text, text + sizeof text, value, std::chars_format::general,
                                   std::numeric_limits<double>::max_digits10);
  return std::string(text, exact.ptr);
}

std::pair<int, int> parse_lag_range(const std::string& text, const std::string& name) {
  const std::size_t dots = text.find("..");
  int first = 0, last = 0;
  if (dots == std::string::npos || !read_exactly(text.substr(0, dots), first) ||
      !read_exactly(text.substr(dots + 2), last)) {
    throw UsageError(name, "expected FIRST..LAST in samples, e.g. 3..40, found '" + text + "'");
  }
  return {first, last};
}

std::map<std::string, std::string> parse_option_pairs(const std::string& text,
                                                      const std::string& name,
                                                      const std::string& expected) {
  std::map<std::string, std::string> out;
  // The next ',' outside brackets: `y=V[:, 0]` names a matrix column.
  const auto next_comma = [&](std::size_t from) {
    int depth = 0;
    for (std::size_t i = from; i < text.size(); ++i) {
      if (text[i] == '[') ++depth;
      if (text[i] == ']') --depth;
      if (text[i] == ',' && depth <= 0) return i;
    }
    return text.size();
  };
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = next_comma(begin);
    const std::string e = text.substr(begin, end - begin);
    const std::size_t eq = e.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == e.size()) {
      throw UsageError(name, "expected " + expected + ", found '" + e + "'");
    }
    out[e.substr(0, eq)] = e.substr(eq + 1);
    begin = end + 1;
  }
  return out;
}

namespace options {
namespace {

long whole(const std::string& text, const std::string& name) {
  long value = 0;
  if (!read_exactly(text, value)) {
    throw UsageError(name, "expected a whole number, found '" + text + "'");
  }
  return value;
}

// A size in bytes: a whole number with an optional unit, k, M, G, T, P or E for powers of 1024
// (kB and KiB alike), in any case.
std::size_t size_in_bytes(const std::string& text, const std::string& name) {
  std::size_t unit_begin = text.size();
  while (unit_begin > 0 && std::isalpha(static_cast<unsigned char>(text[unit_begin - 1]))) {
    --unit_begin;
  }
  std::string unit = text.substr(unit_begin);
  std::transform(unit.begin(), unit.end(), unit.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const std::map<std::string, int> kPowers = {
      {"", 0},    {"b", 0},  {"k", 1},   {"kb", 1},  {"ki", 1}, {"kib", 1}, {"m", 2},
      {"mb", 2},  {"mi", 2}, {"mib", 2}, {"g", 3},   {"gb", 3}, {"gi", 3},  {"gib", 3},
      {"t", 4},   {"tb", 4}, {"ti", 4},  {"tib", 4}, {"p", 5},  {"pb", 5},  {"pi", 5},
      {"pib", 5}, {"e", 6},  {"eb", 6},  {"ei", 6},  {"eib", 6}};
  const auto power = kPowers.find(unit);
  std::string digits = text.substr(0, unit_begin);
  while (!digits.empty() && digits.back() == ' ') digits.pop_back();
  std::size_t value = 1;  // a unit alone is one of it
  if (power == kPowers.end() ||
      (!(digits.empty() && !unit.empty()) && !read_exactly(digits, value)) ||
      value > (std::numeric_limits<std::size_t>::max() >> (10 * power->second))) {
    throw UsageError(
        name, "expected a size in bytes, with k, M or G for powers of 1024, found '" + text + "'");
  }
  return value << (10 * power->second);
}

}  // namespace

std::size_t count(const std::string& text, const std::string& name) {
  std::size_t value = 0;
  if (!read_exactly(text, value)) {
    throw UsageError(name, "expected a whole number, 0 or more, found '" + text + "'");
  }
  return value;
}

std::size_t count_in(const std::string& text, const std::string& name, std::size_t low,
                     std::size_t high) {
  std::size_t value = 0;
  if (!read_exactly(text, value) || value < low || value > high) {
    throw UsageError(name, "expected a whole number from " + std::to_string(low) + " to " +
                               std::to_string(high) + ", found '" + text + "'");
  }
  return value;
}

std::vector<std::string> names(const std::string& text) {
  std::vector<std::string> out;
  std::size_t begin = 0;
  while (begin < text.size()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    out.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  return out;
}

void set_columns(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  for (const auto& [key, column] : parse_option_pairs(text, n, "NAME=COLUMN")) {
    o.identify.record.columns.insert_or_assign(key, column);
  }
}

void set_dt(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.record.dt = parse_option_number(text, n);
}

void set_hold(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.record.hold = parse_input_hold(text, n);
}

void set_input_shift(SelectOptions& o, const Model&, const std::string& text,
                     const std::string& n) {
  o.identify.input_shift = whole(text, n);
}

void set_batches(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.batches = count(text, n);
}

void set_lags(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.lags = parse_lag_range(text, n);
}

void set_integrate(SelectOptions& o, const Model&, const std::string& text, const std::string&) {
  o.identify.integrate = names(text);
}

void set_integrate_corner(SelectOptions& o, const Model&, const std::string& text,
                          const std::string& n) {
  o.identify.integrate_corner = parse_option_number(text, n);
}

void set_skip_rows(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.record.layout.skip_rows = count(text, n);
}

void set_decimal(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  if (text != "." && text != ",") {
    throw UsageError(n, "expected '.' or ',', found '" + text + "'");
  }
  o.identify.record.layout.decimal = text[0];
}

void set_missing(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.record.layout.missing = parse_missing_values(text, n);
}

void set_names(SelectOptions& o, const Model&, const std::string& text, const std::string&) {
  o.identify.record.layout.column_names = names(text);
}

void set_runs(SelectOptions& o, const Model&, const std::string& text, const std::string&) {
  o.identify.record.layout.runs = names(text);
}

void set_dt_from(SelectOptions& o, const Model&, const std::string& text, const std::string&) {
  o.identify.record.layout.dt_from = text;
}

void set_threads(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.record.control.threads = count_in(text, n, 0, 1024);
}

void set_shard_size(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  const std::size_t bytes = size_in_bytes(text, n);
  if (bytes < 1024) {
    throw UsageError(
        n, "expected at least 1k (1024 bytes), found " + std::to_string(bytes) + " bytes");
  }
  o.identify.record.control.shard_bytes = bytes;
}

void set_instruments(SelectOptions& o, const Model& m, const std::string& text,
                     const std::string& n) {
  o.identify.instruments = parse_instrument_list(m, text, n);
}

void set_noise(SelectOptions& o, const Model& m, const std::string& text, const std::string& n) {
  if (text == "auto") {
    o.identify.noise.reset();
    return;
  }
  std::map<std::string, double> out;
  const std::map<std::string, std::string> given =
      text == "none" ? std::map<std::string, std::string>{}
                     : parse_option_pairs(text, n, "NAME=VARIANCE");
  for (const auto& item : given) {
    // Named, not bound: clang 14 lets no lambda capture a structured binding.
    const std::string& state = item.first;
    const std::string& value = item.second;
    const auto& states = m.states();
    if (std::none_of(states.begin(), states.end(),
                     [&](const Declaration& d) { return d.name == state; })) {
      throw UsageError(n, "'" + state + "' is not a state of model " + m.name());
    }
    double variance = 0;
    if (!read_exactly(value, variance) || !std::isfinite(variance) || variance < 0) {
      throw UsageError(
          n, "expected a variance of at least 0 for '" + state + "', found '" + value + "'");
    }
    out[state] = variance;
  }
  o.identify.noise = std::move(out);
}

void set_fix(SelectOptions& o, const Model& m, const std::string& text, const std::string& n) {
  // The values read as --set reads them, exact decimals rounded once (the parameters not fixed
  // at 0, so that none lacks a value).
  const ParameterValues fixed = parse_parameter_values(m, names(text), n);
  ParameterValues every;
  for (const Declaration& p : m.parameters()) every[p.name] = 0.0;
  for (const auto& entry : fixed) every[entry.first] = entry.second;
  const std::vector<GiNaC::numeric> values = parameter_vector(m, every, n);
  for (const auto& entry : fixed) {
    const auto index = static_cast<std::size_t>(m.parameter_index(entry.first));
    o.identify.fixed[entry.first] = values[index].to_double();
  }
}

void set_center(SelectOptions& o, const Model& m, const std::string& text, const std::string&) {
  o.identify.center = text == "all" ? m.channel_names() : names(text);
}

void set_multipliers(SelectOptions& o, const Model& m, const std::string& text,
                     const std::string& n) {
  o.identify.multipliers = parse_multiplier_list(m, text, n);
}

void set_degree(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.degree = static_cast<int>(count_in(text, n, 1, IdentifyOptions::kMaxDegree));
}

void set_method(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.method = parse_method(text, n);
}

void set_weighting(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.identify.weighting = parse_weighting(text, n);
}

void set_extrapolate(SelectOptions& o, const Model&, const std::string& text,
                     const std::string& n) {
  if (text != "dt") throw UsageError(n, "expected dt, found '" + text + "'");
  o.identify.extrapolate = true;
}

void set_refine(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  if (!text.empty()) throw UsageError(n, "takes no value, found '" + text + "'");
  o.identify.refine = true;
}

void set_exhaustive(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.exhaustive = count_in(text, n, 0, SelectOptions::kMaxExhaustive);
}

void set_ranked(SelectOptions& o, const Model&, const std::string& text, const std::string& n) {
  o.ranked = count_in(text, n, 1, 100);
}

void set_validation(SelectOptions& o, const Model&, const std::string& text, const std::string&) {
  o.validation = DataSource::file(text);
}

}  // namespace options
}  // namespace momentid
