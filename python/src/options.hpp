#pragma once
// identify's and select's keyword arguments, read through the library's option table
// (momentid/option_table.hpp): each Python value is turned into the text of its option by the
// kind of value the table gives it, and the table's setters read that text as they read the
// command line's.

#include <pybind11/pybind11.h>

#include <string>
#include <vector>

#include "momentid/option_table.hpp"
#include "momentid/record_options.hpp"

namespace momentid::python {

// The options of `command` ("identify" or "select"), one dict each: flag, keyword, value_name,
// value (the kind: "count", "pairs", ...), default, help, commands and stage.
pybind11::list option_list(const std::string& command);

// The options in `options` ({keyword: value}, None for not given) that option_table() gives
// `command`, as texts named by their keywords. Throws UsageError naming the keyword for a value
// of the wrong type.
std::vector<GivenOption> given_options(const pybind11::dict& options, const std::string& command);

// Lets other Python threads run while a pass reads the data, and Ctrl-C stop it.
void release_during_pass(PassControl& control);

}  // namespace momentid::python
