#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace momentid {

// Where something is in a source: a model file, a command-line option or a data file.
// Lines and columns count from 1; a column counts bytes. `text` is the whole source line, so
// that a message can show it with a caret under `column`.
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;
  std::string text;
};

// The root of every error momentid reports. `exit_code()` is the process exit status the
// command-line tool returns for it (docs/cli/index.md, "Exit status").
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
  virtual int exit_code() const { return 2; }
};

// A wrong command line or options struct: an unknown option, a value out of range, a name the
// model or the data do not have. Exit status 1.
//
// `option()` is the field of the options struct the error concerns ("fixed" for
// IdentifyOptions::fixed), empty when it concerns no one option; `what()` is "fixed: message".
// A message may name other fields too, each written as mention("observe"). Front ends spell the
// fields their own way with text(): the command line `--fix`, Python its keyword `fix`.
//
// Example:
//   throw UsageError("noise", "channel 'v' is not observed (" + UsageError::mention("observe") +
//                                 " y,x)");
//   error.text(flag_of);  // "--noise: channel 'v' is not observed (--observe y,x)"
class UsageError : public Error {
 public:
  explicit UsageError(const std::string& message) : UsageError("", message) {}
  UsageError(std::string option, std::string message);
  int exit_code() const override { return 1; }

  const std::string& option() const { return option_; }
  // The message with the option in front and every mention spelled by `spell`, which takes a
  // field's name.
  std::string text(const std::function<std::string(const std::string&)>& spell) const;
  // A field named inside a message.
  static std::string mention(std::string_view field);

 private:
  std::string option_, message_;
};

// An error located in a source text. `what()` is "file:line:col: message"; `message()` is the
// bare message and `location()` the place, for callers that render the line with a caret. A
// message may name options fields, each written as UsageError::mention("dt"): what() gives the
// field's name, text() spells it as a front end does (`--dt`, `dt`).
class LocatedError : public Error {
 public:
  LocatedError(SourceLocation where, const std::string& message);
  const SourceLocation& location() const { return where_; }
  // The bare message, mentions kept (to build another error from it).
  const std::string& message() const { return message_; }
  // what(), with every mention spelled by `spell`.
  std::string text(const std::function<std::string(const std::string&)>& spell) const;

 private:
  SourceLocation where_;
  std::string message_;
};

// The model text does not follow the grammar (grammar/README.md).
class ParseError : public LocatedError {
 public:
  using LocatedError::LocatedError;
};

// The model parses but does not mean anything momentid can use: an undeclared name, a term
// that is not affine in the parameters, a state without an equation, ...
class ModelError : public LocatedError {
 public:
  using LocatedError::LocatedError;
};

// The lagged equations of a record that shows states only through the column of a derivative
// (y'' = a) need those states themselves: in a nonlinear term, or through a derivative in the lag
// beyond the highest. Forming them from their columns (IdentifyOptions::integrate) with the
// states `states()` lifts it: identify does so by default.
class FormStatesError : public ModelError {
 public:
  FormStatesError(SourceLocation where, const std::string& message, std::vector<std::string> states)
      : ModelError(std::move(where), message), states_(std::move(states)) {}
  const std::vector<std::string>& states() const { return states_; }

 private:
  std::vector<std::string> states_;
};

// A data file that cannot be used: a missing column, a field that is not a finite number, a
// ragged row, non-uniform time steps, too few rows. The location is the file line (from 1) and
// the byte column of the offending field.
class DataError : public LocatedError {
 public:
  using LocatedError::LocatedError;
};

// A pass stopped because its caller asked (PassControl::interrupted): Ctrl-C in a front end.
class Interrupted : public Error {
 public:
  Interrupted() : Error("interrupted") {}
};

// `text` safe to print on a terminal: control characters, the characters that reorder text
// (bidirectional controls such as U+202E) and bytes that are not UTF-8 become '?'; tabs and line
// feeds stay.
std::string printable(std::string_view text);

// Renders a located error as the command-line tool prints it: the `what()` line (its mentions
// spelled by `spell`, when given), then the source line and a caret under the column.
std::string render_with_caret(const LocatedError& error,
                              const std::function<std::string(const std::string&)>& spell = {});

}  // namespace momentid
