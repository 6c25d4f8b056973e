#include "options.hpp"

#include <pybind11/stl.h>

#include <optional>
#include <utility>

#include "momentid/error.hpp"

namespace py = pybind11;

namespace momentid::python {
namespace {

[[noreturn]] void wrong_type(const std::string& keyword, const char* expected,
                             const py::handle value) {
  throw UsageError(keyword, std::string("expected ") + expected + ", found " +
                                py::repr(value).cast<std::string>());
}

// `value` as T, or UsageError saying that it should be `expected`.
template <class T>
T as(const py::handle value, const std::string& keyword, const char* expected) {
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    wrong_type(keyword, expected, value);
  }
}

// A string, or the items of a sequence (not a mapping) as str() writes them, joined by `comma`.
std::string joined(const py::handle value, const std::string& keyword, const char* comma,
                   const char* expected) {
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (!py::isinstance<py::sequence>(value) || py::hasattr(value, "keys")) {
    wrong_type(keyword, expected, value);
  }
  std::string out;
  for (const py::handle item : value) {
    out += (out.empty() ? "" : comma) + py::str(item).cast<std::string>();
  }
  return out;
}

// NAME=VALUE pairs from a mapping, a string value as it is and a number as the shortest text
// that reads back as the same double; a string as it is.
std::string pairs(const py::handle value, const std::string& keyword) {
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (!py::hasattr(value, "items")) wrong_type(keyword, "a mapping of names to values", value);
  std::string out;
  for (const py::handle item : value.attr("items")()) {
    const auto pair = item.cast<py::tuple>();
    const py::handle v = pair[1];
    const std::string text = py::isinstance<py::str>(v)
                                 ? v.cast<std::string>()
                                 : option_number_text(as<double>(v, keyword, "numbers"));
    out += (out.empty() ? "" : ",") + py::str(pair[0]).cast<std::string>() + "=" + text;
  }
  return out;
}

std::string range(const py::handle value, const std::string& keyword) {
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  const auto [first, last] = as<std::pair<int, int>>(value, keyword, "(first, last)");
  return std::to_string(first) + ".." + std::to_string(last);
}

// The text of option `o` for the Python value `value`; nullopt when the value stands for the
// option not given (False for a switch, an empty list or mapping).
std::optional<std::string> text_of(const OptionDescription& o, const py::handle value) {
  const std::string keyword(o.keyword);
  std::string text;
  switch (o.value) {
    case OptionValue::kCount:
      return std::to_string(as<std::size_t>(value, keyword, "a whole number, 0 or more"));
    case OptionValue::kWhole:
      return std::to_string(as<long>(value, keyword, "a whole number"));
    case OptionValue::kNumber:
      return option_number_text(as<double>(value, keyword, "a number"));
    case OptionValue::kText:
    case OptionValue::kChoice:
    case OptionValue::kRecord:
      if (!py::isinstance<py::str>(value)) wrong_type(keyword, "a string", value);
      return value.cast<std::string>();
    case OptionValue::kSwitch:
      if (!py::isinstance<py::bool_>(value)) wrong_type(keyword, "True or False", value);
      if (!value.cast<bool>()) return std::nullopt;
      return std::string(o.value_name);
    case OptionValue::kSize:
      if (py::isinstance<py::str>(value)) return value.cast<std::string>();
      return std::to_string(as<std::size_t>(value, keyword, "a size in bytes"));
    case OptionValue::kRange:
      return range(value, keyword);
    case OptionValue::kNames:
      text = joined(value, keyword, ",", "a name or a list of names");
      break;
    case OptionValue::kMonomials:
      text = joined(value, keyword, ", ", "monomials, as a list or in one string");
      break;
    case OptionValue::kPairs:
      text = pairs(value, keyword);
      break;
  }
  if (!text.empty()) return text;
  if (!o.when_empty.empty()) return std::string(o.when_empty);
  return std::nullopt;
}

const char* commands_of(OptionCommands commands) {
  switch (commands) {
    case OptionCommands::kIdentify:
      return "identify";
    case OptionCommands::kSelect:
      return "select";
    case OptionCommands::kBoth:
      break;
  }
  return "identify select";
}

}  // namespace

py::list option_list(const std::string& command) {
  py::list out;
  for (const OptionDescription* o : options_of(command)) {
    py::dict entry;
    entry["flag"] = std::string(o->flag);
    entry["keyword"] = std::string(o->keyword);
    entry["value_name"] = std::string(o->value_name);
    entry["value"] = to_string(o->value);
    entry["default"] = std::string(o->default_text);
    entry["help"] = std::string(o->help);
    entry["commands"] = py::str(commands_of(o->commands)).attr("split")();
    entry["stage"] = o->stage == OptionStage::kRecord ? "record" : "model";
    out.append(entry);
  }
  return out;
}

std::vector<GivenOption> given_options(const py::dict& options, const std::string& command) {
  std::vector<GivenOption> out;
  for (const OptionDescription* o : options_of(command)) {
    const py::str keyword(std::string(o->keyword));
    if (!options.contains(keyword) || options[keyword].is_none()) continue;
    if (std::optional<std::string> text = text_of(*o, options[keyword])) {
      out.push_back({o, std::move(*text), std::string(o->keyword)});
    }
  }
  return out;
}

void release_during_pass(PassControl& control) {
  // Other Python threads run while the data are read; the rest of a call keeps the GIL. The
  // library lets go of its algebra lock before this and takes it back after, so the GIL is
  // always taken first.
  control.around_pass = [](const std::function<void()>& read) {
    py::gil_scoped_release release;
    read();
  };
  // Ctrl-C: Python's handler runs (on the main thread; the pass is read from the calling one)
  // and leaves KeyboardInterrupt set, which the exception translator raises once the pass has
  // stopped.
  control.interrupted = [] {
    py::gil_scoped_acquire hold;
    return PyErr_CheckSignals() != 0;
  };
}

}  // namespace momentid::python
