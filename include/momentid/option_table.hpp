#pragma once
// The options of identify and select, each described once: its command-line flag, its Python
// keyword, the name and kind of its value, its default as the docs state it, its one-line help,
// and the setter that fills SelectOptions (whose `identify` member is IdentifyOptions) from its
// text. The command line adds its options by iterating the table, the Python module reads its
// keyword arguments through it, and a test (tests/option_docs.py) holds the docs' option tables
// and the Python signatures to it; a new option is one more entry of option_table().
//
// A setter names its option in messages by the name the caller gives (`--lags` on the command
// line, `lags` in Python); errors found later name the options field (UsageError::option()),
// which option_of_field() maps back to the entry, so that a front end spells it the same way.
//
// Example:
//   SelectOptions options;
//   const std::vector<GivenOption> given = {{find_option("lags"), "3..40", "--lags"}};
//   const Model completed = apply_options(given, model, source, options);
//   options.identify.lags;  // {3, 40}

#include <array>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "momentid/select.hpp"

namespace momentid {

class Model;

// What an option's value is, which says how a front end turns a value of its own into the text
// the setter reads (the Python module: an int into "12", a dict into "k=4,c=0.5").
enum class OptionValue {
  kCount,      // a whole number, 0 or more
  kWhole,      // a whole number
  kNumber,     // a number
  kText,       // any text: a name, a path
  kChoice,     // one of the names its value name lists ("sample|zoh")
  kNames,      // names, joined by commas ("y,v"); one name alone as it is
  kMonomials,  // monomials, joined by ", " ("y, y^3"), as the model language lists them
  kPairs,      // NAME=VALUE pairs joined by commas, from a mapping of names to values
  kRange,      // FIRST..LAST, from a pair (first, last)
  kSwitch,     // on or off: on is the option with its value name as its text ("dt")
  kSize,       // a size in bytes, with k, M or G for powers of 1024
  kRecord,     // a data file; a front end may give a record of its own instead
};
// "count", "whole", "number", "text", "choice", "names", "monomials", "pairs", "range",
// "switch", "size", "record".
std::string to_string(OptionValue value);

// When a setter runs: kRecord before the model is completed by the columns that hold a state's
// derivative (declare_derivative_columns), kModel after, against the completed model.
enum class OptionStage { kRecord, kModel };

// The commands that take an option: both identify and select, or one of them.
enum class OptionCommands { kBoth, kIdentify, kSelect };

// Sets the option from `text` into `options`, checking it (against `model` at stage kModel) and
// naming it `name` in messages.
using OptionSetter = void (*)(SelectOptions& options, const Model& model, const std::string& text,
                              const std::string& name);

struct OptionDescription {
  std::string_view flag;        // "--lags"
  std::string_view keyword;     // "lags"
  std::string_view field;       // the field its errors name (UsageError::option()): "fixed"
  std::string_view value_name;  // "FIRST..LAST"
  OptionValue value = OptionValue::kText;
  std::string_view default_text;  // as the docs state it; empty: none
  std::string_view help;
  OptionCommands commands = OptionCommands::kBoth;
  OptionStage stage = OptionStage::kRecord;
  // The command line takes it more than once (`--fix k=4 --fix c=1`): the texts, joined by
  // commas, are the one text of the option.
  bool repeated = false;
  // The keywords of the options that cannot be given with this one (empty: none).
  std::array<std::string_view, 2> excludes{};
  // The text that an empty list or mapping stands for; empty: the option is then not given.
  std::string_view when_empty;
  OptionSetter set = nullptr;
};

// Every option, in the order the docs' tables and --help show them.
std::span<const OptionDescription> option_table();
// The options of "identify" or "select", in the table's order.
std::vector<const OptionDescription*> options_of(std::string_view command);
// The option with this keyword or flag; nullptr when none has it.
const OptionDescription* find_option(std::string_view keyword_or_flag);
// The option whose errors name `field` ("fixed" is --fix); nullptr when none.
const OptionDescription* option_of_field(std::string_view field);

// An option as a front end received it: its text and the name its messages give it.
struct GivenOption {
  const OptionDescription* option = nullptr;
  std::string text;
  std::string name;
};

// Sets the given options into `options`: those of stage kRecord, then the columns that hold a
// state's derivative declared (declare_derivative_columns, with the metadata of `source`), then
// those of stage kModel against the completed model, which is returned. Throws UsageError for
// two options that exclude each other, and what the setters throw.
Model apply_options(const std::vector<GivenOption>& given, const Model& model,
                    const DataSource& source, SelectOptions& options);

// The given options, each of stage kRecord (std::invalid_argument otherwise), set into a
// RecordOptions: for a front end's commands that read a record but take no other option of the
// table (check, validate), with the same checks and messages.
RecordOptions record_options(const std::vector<GivenOption>& given);

// The number `text` is as the command line has always read one (the nearest long double,
// rounded to a double), or UsageError naming `name`; and the shortest text that it reads back
// as `value`, for a front end that holds a double.
double parse_option_number(const std::string& text, const std::string& name);
std::string option_number_text(double value);
// FIRST..LAST (`--lags 3..40`): the first and the last lag, or UsageError naming `name`.
std::pair<int, int> parse_lag_range(const std::string& text, const std::string& name);
// NAME=VALUE pairs separated by commas outside brackets (`y=V[:, 0]` names a matrix column), a
// later pair of a name winning; UsageError naming `name` for an entry that is not one, described
// as `expected` ("NAME=COLUMN").
std::map<std::string, std::string> parse_option_pairs(const std::string& text,
                                                      const std::string& name,
                                                      const std::string& expected);

}  // namespace momentid
