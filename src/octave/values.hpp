#pragma once
// Octave's and MATLAB's values (mxArray) to and from what the library takes and gives: the
// JSON values of results as structs, and the texts of options from numbers, strings, cell
// arrays and structs. Every function takes the name the caller gave a value, for messages.

#include <mex.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "momentid/json.hpp"

namespace momentid::mex {

// A JSON value as Octave holds it: an object as a struct (or, when a key is not a valid field
// name, a struct array of `name` and `value`), an array of numbers (null as NaN) as a row
// vector, of equally long arrays of numbers as a matrix (a row each), of booleans as a logical
// row, of strings as a cell row, of objects with the same valid keys as a struct row; any other
// array as a cell row; an empty array as {}; null as [].
mxArray* to_octave(const nlohmann::ordered_json& value);

// A field name MATLAB accepts: a letter, then letters, digits and underscores, 63 at most.
bool valid_field_name(const std::string& name);

// `value` as a string: a char row. UsageError "name: expected TEXT, found ..." otherwise.
std::string text(const mxArray* value, const std::string& name, const char* expected = "a string");

// A real scalar number, or UsageError naming `name`.
double number(const mxArray* value, const std::string& name, const char* expected = "a number");

// A whole number within lowest..highest, or UsageError naming `name`.
std::int64_t whole(const mxArray* value, const std::string& name, std::int64_t lowest,
                   std::int64_t highest, const char* expected);

// The values of a real numeric or logical array, as doubles, in Octave's (column-major) order.
// UsageError naming `name` for any other value.
std::vector<double> numbers_of(const mxArray* value, const std::string& name, const char* expected);

// true or false (a logical or a number 0 or 1), or UsageError naming `name`.
bool truth(const mxArray* value, const std::string& name);

// A string, or the strings of a cell array (or the numbers of a vector) as texts joined by
// `comma`.
std::string joined(const mxArray* value, const std::string& name, const char* comma,
                   const char* expected);

// NAME=VALUE pairs joined by commas: from a struct (a field each), a cell array of names and
// values ({'y''', 'acc'; 'x', 'force'} or {'y''', 'acc', 'x', 'force'}), or a string as it is
// (NAME=VALUE,...). A number is written as the shortest text that reads back as the same double.
std::string pairs(const mxArray* value, const std::string& name);

// The same pairs, as a list of (name, text).
std::vector<std::pair<std::string, std::string>> pair_list(const mxArray* value,
                                                           const std::string& name);

// A short description of a value for messages: "a 3x1 double", "the string 'abc'".
std::string describe(const mxArray* value);

}  // namespace momentid::mex
