// Parameter values by name (momentid/parameters.hpp), read from `NAME=VALUE` assignments and
// turned into the model's positional values.

#include "momentid/parameters.hpp"

#include <charconv>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "momentid/algebra_lock.hpp"
#include "momentid/error.hpp"
#include "momentid/simulate.hpp"

namespace momentid {

using GiNaC::numeric;

namespace {

// [+-] digits [. digits] [e [+-] digits], with digits on at least one side of the point.
bool is_decimal(std::string_view text) {
  std::size_t i = 0;
  auto digits = [&] {
    const std::size_t start = i;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9') ++i;
    return i - start;
  };
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  std::size_t mantissa = digits();
  if (i < text.size() && text[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == text.size();
}

}  // namespace

namespace {

// The exact value of the decimal `text` (is_decimal), for parameter `name` of `option`.
numeric exact_value(const std::string& name, const std::string& text, const std::string& option) {
  if (!is_decimal(text)) {
    throw UsageError(option, "the value of '" + name + "' must be a number, found '" + text + "'");
  }
  const bool negative = text[0] == '-';
  const std::string digits = (text[0] == '-' || text[0] == '+') ? text.substr(1) : text;
  try {
    const numeric v = parse_exact_number(digits);
    return negative ? -v : v;
  } catch (const std::out_of_range& e) {
    throw UsageError(option, e.what());
  }
}

void require_parameter(const Model& model, const std::string& name, const std::string& option) {
  if (model.parameter_index(name) >= 0) return;
  std::string known;
  for (const Declaration& d : model.parameters()) known += (known.empty() ? "" : ", ") + d.name;
  throw UsageError(option, "'" + name + "' is not a parameter of model " + model.name() +
                               " (parameters: " + known + ")");
}

}  // namespace

ParameterValue ParameterValue::exact(std::string text) {
  ParameterValue out;
  const std::string_view digits = text.starts_with('+') ? std::string_view(text).substr(1) : text;
  std::from_chars(digits.data(), digits.data() + digits.size(), out.value);
  out.decimal = std::move(text);
  return out;
}

ParameterValues parse_parameter_values(const Model& model,
                                       const std::vector<std::string>& assignments,
                                       const std::string& option) {
  const AlgebraLock lock;
  ParameterValues out;
  for (const std::string& a : assignments) {
    const std::size_t eq = a.find('=');
    if (eq == std::string::npos) {
      throw UsageError(option, "expected NAME=VALUE, found '" + a + "'");
    }
    const std::string name = a.substr(0, eq), text = a.substr(eq + 1);
    require_parameter(model, name, option);
    exact_value(name, text, option);  // refuses a bad number where it is given
    out.insert_or_assign(name, ParameterValue::exact(text));
  }
  return out;
}

std::vector<numeric> parameter_vector(const Model& model, const ParameterValues& values,
                                      const std::string& option) {
  const AlgebraLock lock;
  for (const auto& entry : values) require_parameter(model, entry.first, option);
  std::vector<numeric> out;
  for (const Declaration& p : model.parameters()) {
    const auto given = values.find(p.name);
    if (given == values.end() && !p.value) {
      throw ModelError(p.where, "parameter '" + p.name +
                                    "' has no value: give a nominal value in the model or " +
                                    UsageError::mention("parameters") + " " + p.name + "=VALUE");
    }
    if (given == values.end()) {
      out.push_back(*p.value);
    } else if (!given->second.decimal.empty()) {
      out.push_back(exact_value(p.name, given->second.decimal, option));
    } else {
      // As a number read from a file has always been taken: the double itself.
      out.emplace_back(given->second.value);
    }
  }
  return out;
}

}  // namespace momentid
