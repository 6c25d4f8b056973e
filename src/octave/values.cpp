#include "values.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>

#include "momentid/error.hpp"
#include "momentid/option_table.hpp"

namespace momentid::mex {
namespace {

using Json = nlohmann::ordered_json;

double number_or_nan(const Json& value) {
  return value.is_number() ? value.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

bool numeric(const Json& value) { return value.is_number() || value.is_null(); }

bool all_numbers(const Json& array) { return std::all_of(array.begin(), array.end(), numeric); }

// An array of arrays of numbers, all as long as the first and not empty: a matrix.
bool matrix_rows(const Json& array) {
  const Json& first = array.front();
  if (!first.is_array() || first.empty()) return false;
  return std::all_of(array.begin(), array.end(), [&](const Json& row) {
    return row.is_array() && row.size() == first.size() && all_numbers(row);
  });
}

// Objects with the same keys, in the same order, each a valid field name.
bool same_objects(const Json& array) {
  const Json& first = array.front();
  if (!first.is_object()) return false;
  for (const auto& [key, v] : first.items()) {
    if (!valid_field_name(key)) return false;
  }
  return std::all_of(array.begin(), array.end(), [&](const Json& item) {
    if (!item.is_object() || item.size() != first.size()) return false;
    auto a = item.begin();
    for (auto b = first.begin(); b != first.end(); ++a, ++b) {
      if (a.key() != b.key()) return false;
    }
    return true;
  });
}

mxArray* structs(const Json& array) {
  std::vector<std::string> keys;
  for (const auto& [key, v] : array.front().items()) keys.push_back(key);
  std::vector<const char*> names;
  for (const std::string& k : keys) names.push_back(k.c_str());
  mxArray* out =
      mxCreateStructMatrix(1, array.size(), static_cast<int>(names.size()), names.data());
  for (std::size_t i = 0; i < array.size(); ++i) {
    for (std::size_t f = 0; f < keys.size(); ++f) {
      mxSetFieldByNumber(out, i, static_cast<int>(f), to_octave(array[i][keys[f]]));
    }
  }
  return out;
}

mxArray* object(const Json& value) {
  bool valid = true;
  for (const auto& [key, v] : value.items()) valid = valid && valid_field_name(key);
  if (!valid) {
    // Keys such as "E[y^2]": a struct array of name and value.
    const char* fields[] = {"name", "value"};
    mxArray* out = mxCreateStructMatrix(1, value.size(), 2, fields);
    std::size_t i = 0;
    for (const auto& [key, v] : value.items()) {
      mxSetFieldByNumber(out, i, 0, mxCreateString(key.c_str()));
      mxSetFieldByNumber(out, i, 1, to_octave(v));
      ++i;
    }
    return out;
  }
  mxArray* out = mxCreateStructMatrix(1, 1, 0, nullptr);
  for (const auto& [key, v] : value.items()) {
    const int field = mxAddField(out, key.c_str());
    mxSetFieldByNumber(out, 0, field, to_octave(v));
  }
  return out;
}

mxArray* array(const Json& value) {
  const std::size_t n = value.size();
  if (n == 0) return mxCreateCellMatrix(0, 0);
  if (all_numbers(value)) {
    mxArray* out = mxCreateDoubleMatrix(1, n, mxREAL);
    double* into = mxGetPr(out);
    for (std::size_t i = 0; i < n; ++i) into[i] = number_or_nan(value[i]);
    return out;
  }
  if (matrix_rows(value)) {
    const std::size_t columns = value.front().size();
    mxArray* out = mxCreateDoubleMatrix(n, columns, mxREAL);
    double* into = mxGetPr(out);  // column-major
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < columns; ++j) into[j * n + i] = number_or_nan(value[i][j]);
    }
    return out;
  }
  if (std::all_of(value.begin(), value.end(), [](const Json& v) { return v.is_boolean(); })) {
    mxArray* out = mxCreateLogicalMatrix(1, n);
    mxLogical* into = mxGetLogicals(out);
    for (std::size_t i = 0; i < n; ++i) into[i] = value[i].get<bool>();
    return out;
  }
  if (same_objects(value)) return structs(value);
  mxArray* out = mxCreateCellMatrix(1, n);
  for (std::size_t i = 0; i < n; ++i) mxSetCell(out, i, to_octave(value[i]));
  return out;
}

[[noreturn]] void wrong(const std::string& name, const char* expected, const mxArray* value) {
  throw UsageError(name, std::string("expected ") + expected + ", found " + describe(value));
}

bool real_numbers(const mxArray* value) {
  return mxIsNumeric(value) && !mxIsComplex(value) && !mxIsSparse(value);
}

// The text an element of a cell array or a field of a struct stands for in a pair: a string
// as it is, a number as the shortest text that reads back as the same double.
std::string pair_value(const mxArray* value, const std::string& name) {
  if (mxIsChar(value)) return text(value, name);
  return option_number_text(number(value, name, "a number or a string"));
}

}  // namespace

bool valid_field_name(const std::string& name) {
  if (name.empty() || name.size() > 63 || !std::isalpha(static_cast<unsigned char>(name[0])))
    return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

mxArray* to_octave(const Json& value) {
  switch (value.type()) {
    case Json::value_t::object:
      return object(value);
    case Json::value_t::array:
      return array(value);
    case Json::value_t::string:
      return mxCreateString(value.get<std::string>().c_str());
    case Json::value_t::boolean:
      return mxCreateLogicalScalar(value.get<bool>());
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float:
      return mxCreateDoubleScalar(value.get<double>());
    default:  // null, and the kinds JSON values here never hold
      return mxCreateDoubleMatrix(0, 0, mxREAL);
  }
}

std::string describe(const mxArray* value) {
  if (mxIsChar(value) && mxGetM(value) <= 1) {
    char* chars = mxArrayToString(value);
    std::string out = std::string("the string '") + (chars ? chars : "") + "'";
    mxFree(chars);
    return out;
  }
  const std::string size = std::to_string(mxGetM(value)) + "x" + std::to_string(mxGetN(value));
  if (real_numbers(value) && mxGetNumberOfElements(value) == 1) {
    return "the number " + option_number_text(mxGetScalar(value));
  }
  return "a " + size + " " + mxGetClassName(value);
}

std::string text(const mxArray* value, const std::string& name, const char* expected) {
  if (!mxIsChar(value) || mxGetM(value) > 1) wrong(name, expected, value);
  char* chars = mxArrayToString(value);
  if (chars == nullptr) wrong(name, expected, value);
  std::string out(chars);
  mxFree(chars);
  return out;
}

double number(const mxArray* value, const std::string& name, const char* expected) {
  if (!real_numbers(value) || mxGetNumberOfElements(value) != 1) wrong(name, expected, value);
  return mxGetScalar(value);
}

std::int64_t whole(const mxArray* value, const std::string& name, std::int64_t lowest,
                   std::int64_t highest, const char* expected) {
  const double x = number(value, name, expected);
  if (!(x == std::floor(x)) || x < static_cast<double>(lowest) ||
      x > static_cast<double>(highest)) {
    wrong(name, expected, value);
  }
  return static_cast<std::int64_t>(x);
}

std::vector<double> numbers_of(const mxArray* value, const std::string& name,
                               const char* expected) {
  if (!(real_numbers(value) || mxIsLogical(value))) wrong(name, expected, value);
  const std::size_t n = mxGetNumberOfElements(value);
  std::vector<double> out(n);
  const void* data = mxGetData(value);
  const auto copy = [&](const auto* typed) { std::copy(typed, typed + n, out.begin()); };
  switch (mxGetClassID(value)) {
    case mxDOUBLE_CLASS:
      copy(static_cast<const double*>(data));
      break;
    case mxSINGLE_CLASS:
      copy(static_cast<const float*>(data));
      break;
    case mxINT8_CLASS:
      copy(static_cast<const std::int8_t*>(data));
      break;
    case mxUINT8_CLASS:
      copy(static_cast<const std::uint8_t*>(data));
      break;
    case mxINT16_CLASS:
      copy(static_cast<const std::int16_t*>(data));
      break;
    case mxUINT16_CLASS:
      copy(static_cast<const std::uint16_t*>(data));
      break;
    case mxINT32_CLASS:
      copy(static_cast<const std::int32_t*>(data));
      break;
    case mxUINT32_CLASS:
      copy(static_cast<const std::uint32_t*>(data));
      break;
    case mxINT64_CLASS:
      copy(static_cast<const std::int64_t*>(data));
      break;
    case mxUINT64_CLASS:
      copy(static_cast<const std::uint64_t*>(data));
      break;
    case mxLOGICAL_CLASS:
      copy(static_cast<const mxLogical*>(data));
      break;
    default:
      wrong(name, expected, value);
  }
  return out;
}

bool truth(const mxArray* value, const std::string& name) {
  if ((mxIsLogical(value) || real_numbers(value)) && mxGetNumberOfElements(value) == 1) {
    const double x = mxGetScalar(value);
    if (x == 0 || x == 1) return x == 1;
  }
  wrong(name, "true or false", value);
}

std::string joined(const mxArray* value, const std::string& name, const char* comma,
                   const char* expected) {
  if (mxIsChar(value)) return text(value, name, expected);
  std::string out;
  if (mxIsCell(value)) {
    for (std::size_t i = 0; i < mxGetNumberOfElements(value); ++i) {
      const mxArray* item = mxGetCell(value, i);
      if (item == nullptr) wrong(name, expected, value);
      out += (i ? comma : "") + pair_value(item, name);
    }
    return out;
  }
  const std::vector<double> x = numbers_of(value, name, expected);
  for (std::size_t i = 0; i < x.size(); ++i) out += (i ? comma : "") + option_number_text(x[i]);
  return out;
}

std::vector<std::pair<std::string, std::string>> pair_list(const mxArray* value,
                                                           const std::string& name) {
  std::vector<std::pair<std::string, std::string>> out;
  if (mxIsChar(value)) {
    for (auto& pair : parse_option_pairs(text(value, name), name, "NAME=VALUE")) {
      out.push_back(std::move(pair));
    }
    return out;
  }
  if (mxIsStruct(value) && mxGetNumberOfElements(value) == 1) {
    for (int f = 0; f < mxGetNumberOfFields(value); ++f) {
      const std::string field = mxGetFieldNameByNumber(value, f);
      const mxArray* item = mxGetFieldByNumber(value, 0, f);
      if (item == nullptr) wrong(name + "." + field, "a number or a string", value);
      out.emplace_back(field, pair_value(item, name + "." + field));
    }
    return out;
  }
  if (mxIsCell(value) && mxGetNumberOfElements(value) % 2 == 0) {
    // {name, value; name, value} (a row each) or {name, value, name, value}.
    const std::size_t n = mxGetNumberOfElements(value) / 2;
    const bool rows = mxGetN(value) == 2 && mxGetM(value) == n;
    for (std::size_t i = 0; i < n; ++i) {
      const mxArray* key = mxGetCell(value, rows ? i : 2 * i);
      const mxArray* item = mxGetCell(value, rows ? i + n : 2 * i + 1);
      if (key == nullptr || item == nullptr) wrong(name, "names and values", value);
      const std::string k = text(key, name, "names and values, each name a string");
      out.emplace_back(k, pair_value(item, name + " '" + k + "'"));
    }
    return out;
  }
  wrong(name, "a struct, a cell array of names and values, or a string NAME=VALUE,...", value);
}

std::string pairs(const mxArray* value, const std::string& name) {
  if (mxIsChar(value)) return text(value, name);
  std::string out;
  for (const auto& [key, v] : pair_list(value, name)) {
    out += (out.empty() ? "" : ",") + key + "=" + v;
  }
  return out;
}

}  // namespace momentid::mex
