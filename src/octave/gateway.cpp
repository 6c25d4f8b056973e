// The compiled part of momentid's Octave and MATLAB functions (momentid_*.m beside it are the
// rest): one MEX gateway, `momentid_mex(COMMAND, ...)`, that runs the library on Octave's values
// and returns structs. It uses the MEX interface only, so that the same source builds with Octave's
// `mkoctfile --mex` and with MATLAB's `mex`; Ctrl-C is asked of Octave (or of MATLAB's
// utIsInterruptPending) while a pass reads the data.
//
//   momentid_mex('derive',   MODEL, NAME, VALUE, ...)
//   momentid_mex('identify', MODEL, DATA, DATA_NAME, NAME, VALUE, ...)   and select, check,
//                                                                       validate
//   momentid_mex('simulate', MODEL, NAME, VALUE, ...)
//
// MODEL is a model file's path (one line ending in .mom) or a model's text; DATA a file name, a
// cell array of file names, or a struct of column vectors (with an optional field `metadata`).

#include <mex.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "momentid/convert.hpp"
#include "momentid/momentid.hpp"
#include "values.hpp"

#if defined(HAVE_OCTAVE)
#include <octave/quit.h>
#else
extern "C" bool utIsInterruptPending();
#endif

namespace momentid::mex {
namespace {

// --- arguments ------------------------------------------------------------------------------

// The NAME, VALUE pairs of a call, names compared without case; each is taken once, and
// finish() refuses any left over.
class Arguments {
 public:
  Arguments(int count, const mxArray* const* values, const std::string& function)
      : function_(function) {
    if (count % 2 != 0) {
      throw UsageError(function + ": expected NAME, VALUE pairs after the arguments, found " +
                       std::to_string(count) + (count == 1 ? " value" : " values"));
    }
    for (int i = 0; i < count; i += 2) {
      std::string name = text(values[i], "option name", "an option's name");
      std::transform(name.begin(), name.end(), name.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      given_.push_back({name, values[i + 1], false});
    }
  }

  // The value of option `name`, nullptr when not given ([], an empty double array, counts as
  // not given; an empty string, cell array or struct is a value, as in Python).
  const mxArray* take(const std::string& name) {
    const mxArray* out = nullptr;
    for (Given& g : given_) {
      if (g.name != name) continue;
      g.taken = true;
      out = mxIsDouble(g.value) && mxIsEmpty(g.value) ? nullptr : g.value;
    }
    return out;
  }

  // Throws UsageError for an option not taken, listing those of the function.
  void finish(const std::vector<std::string>& known) const {
    for (const Given& g : given_) {
      if (g.taken) continue;
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      throw UsageError(function_ + ": unknown option '" + g.name + "'; expected one of " + list);
    }
  }

 private:
  struct Given {
    std::string name;
    const mxArray* value;
    bool taken;
  };
  std::string function_;
  std::vector<Given> given_;
};

// The options of the record that check and validate take, as identify takes them.
const std::vector<std::string> kRecordNames = {"columns", "dt",      "input_hold", "skip_rows",
                                               "decimal", "missing", "names",      "runs",
                                               "dt_from", "threads", "shard_size"};

std::optional<double> optional_number(Arguments& args, const std::string& name) {
  if (const mxArray* v = args.take(name)) return number(v, name);
  return std::nullopt;
}
// A whole number from 0 to `most`.
std::optional<std::int64_t> optional_count(Arguments& args, const std::string& name,
                                           std::int64_t most = std::int64_t{1} << 53) {
  if (const mxArray* v = args.take(name)) {
    return whole(v, name, 0, most,
                 most == std::numeric_limits<int>::max() ? "a whole number from 0 to 2^31 - 1"
                                                         : "a whole number, 0 or more");
  }
  return std::nullopt;
}
constexpr std::int64_t kMostInt = std::numeric_limits<int>::max();
std::optional<std::string> optional_text(Arguments& args, const std::string& name) {
  if (const mxArray* v = args.take(name)) return text(v, name);
  return std::nullopt;
}
std::vector<std::string> names_of(const mxArray* value, const std::string& name) {
  std::vector<std::string> out;
  if (mxIsChar(value)) return {text(value, name)};
  if (!mxIsCell(value)) text(value, name, "a name or a cell array of names");  // throws
  for (std::size_t i = 0; i < mxGetNumberOfElements(value); ++i) {
    const mxArray* item = mxGetCell(value, i);
    out.push_back(item ? text(item, name, "a cell array of names") : "");
  }
  return out;
}

void check_interrupt(PassControl& control) {
  control.interrupted = [] {
#if defined(HAVE_OCTAVE)
    return octave_interrupt_state > 0;
#else
    return utIsInterruptPending();
#endif
  };
}

// The options of an identify or select option table entry, as the text its setter reads.
std::optional<std::string> option_text(const OptionDescription& o, const mxArray* value);

// check's and validate's record options, set and checked by the option table's setters.
RecordOptions record_options(Arguments& args) {
  std::vector<GivenOption> given;
  for (const std::string& keyword : kRecordNames) {
    const OptionDescription* option = find_option(keyword);
    if (const mxArray* value = args.take(keyword)) {
      if (std::optional<std::string> text = option_text(*option, value)) {
        given.push_back({option, std::move(*text), keyword});
      }
    }
  }
  RecordOptions out = momentid::record_options(given);
  check_interrupt(out.control);
  return out;
}

// --- models and data ------------------------------------------------------------------------

Model model_of(const mxArray* value) {
  const std::string given = text(value, "model", "a model file's path or a model's text");
  if (given.find('\n') == std::string::npos && given.ends_with(".mom")) {
    return parse_model_file(given);
  }
  return parse_model(given, "<model>");
}

// The columns of a struct, read in place when they are double vectors, copied otherwise (held
// in `copies`, which the source must not outlive).
DataSource data_source(const mxArray* data, const std::string& name,
                       std::vector<std::vector<double>>& copies) {
  if (mxIsChar(data)) return DataSource::file(text(data, "data"));
  if (mxIsCell(data)) {
    const std::vector<std::string> files = names_of(data, "data");
    if (files.size() == 1) return DataSource::file(files.front());
    return DataSource::files(files);
  }
  if (!mxIsStruct(data) || mxGetNumberOfElements(data) != 1) {
    throw UsageError(
        "data: expected a file name, a cell array of file names or a struct of "
        "column vectors, found " +
        describe(data));
  }
  MemoryData memory;
  memory.name = name;
  bool first = true;
  for (int f = 0; f < mxGetNumberOfFields(data); ++f) {
    const std::string column = mxGetFieldNameByNumber(data, f);
    const mxArray* values = mxGetFieldByNumber(data, 0, f);
    if (column == "metadata") {
      // The record's metadata as its file would carry it, '-' written '_' (input_hold).
      DataMetadata::Line line;
      for (auto [key, text] : pair_list(values, "data.metadata")) {
        std::replace(key.begin(), key.end(), '_', '-');
        line.emplace_back(key, text);
      }
      if (!line.empty()) memory.metadata.add_line(std::move(line));
      continue;
    }
    if (values == nullptr || !mxIsNumeric(values) || mxIsComplex(values) || mxIsSparse(values) ||
        std::min(mxGetM(values), mxGetN(values)) > 1 || mxGetNumberOfDimensions(values) > 2) {
      throw UsageError("data." + column + ": expected a vector of real numbers, found " +
                       (values ? describe(values) : "nothing"));
    }
    const std::size_t rows = mxGetNumberOfElements(values);
    if (first) {
      memory.rows = rows;
      first = false;
    } else if (rows != memory.rows) {
      throw UsageError("data." + column + " has " + std::to_string(rows) + " values, but data." +
                       memory.columns.front().name + " has " + std::to_string(memory.rows) +
                       ": every column needs one value per sample");
    }
    const double* at = nullptr;
    if (mxIsDouble(values)) {
      at = mxGetPr(values);
    } else {
      at = copies.emplace_back(numbers_of(values, "data." + column, "a vector of real numbers"))
               .data();
    }
    memory.columns.push_back({column, at, 1});
  }
  if (first) throw UsageError("data: the struct has no columns");
  return DataSource::memory(std::move(memory));
}

// --- results --------------------------------------------------------------------------------

void set(mxArray* s, const char* field, mxArray* value) {
  int f = mxGetFieldNumber(s, field);
  if (f < 0) f = mxAddField(s, field);
  if (f < 0) throw Error(std::string("cannot add the field '") + field + "' to a struct");
  mxSetFieldByNumber(s, 0, f, value);
}

// A model variable's name as the field of a struct of series: UsageError for one MATLAB cannot
// hold (`_y`, longer than 63 characters) or that `taken` already names (t, run, metadata).
const char* variable_field(const std::string& name, const std::vector<std::string>& taken) {
  if (!valid_field_name(name)) {
    throw UsageError("'" + name +
                     "' cannot name a field of a struct (a letter, then letters, "
                     "digits and underscores, 63 at most): rename the model's variable");
  }
  if (std::find(taken.begin(), taken.end(), name) != taken.end()) {
    throw UsageError("the model's variable '" + name + "' would replace the field '" + name +
                     "' of the result: rename it");
  }
  return name.c_str();
}

mxArray* column(const std::vector<double>& values) {
  mxArray* out = mxCreateDoubleMatrix(values.size(), 1, mxREAL);
  std::copy(values.begin(), values.end(), mxGetPr(out));
  return out;
}

mxArray* strings(const std::vector<std::string>& values) {
  mxArray* out = mxCreateCellMatrix(values.size(), 1);
  for (std::size_t i = 0; i < values.size(); ++i) {
    mxSetCell(out, i, mxCreateString(values[i].c_str()));
  }
  return out;
}

// A result's JSON value as a struct, with its report as the command line prints it (`text`).
mxArray* result(const nlohmann::ordered_json& value, const std::string& report) {
  mxArray* out = to_octave(value);
  set(out, "text", mxCreateString(report.c_str()));
  return out;
}

// The estimates as vectors in the model's order: param_names, params, bse (NaN: not
// identified), as identify's and select's `parameters` give them.
void add_vectors(mxArray* out, const nlohmann::ordered_json& parameters) {
  std::vector<std::string> names;
  std::vector<double> estimates, errors;
  const auto number_of = [](const nlohmann::ordered_json& v) {
    return v.is_number() ? v.get<double>() : mxGetNaN();
  };
  for (const auto& [name, p] : parameters.items()) {
    names.push_back(name);
    estimates.push_back(number_of(p["estimate"]));
    errors.push_back(number_of(p["std_error"]));
  }
  set(out, "param_names", strings(names));
  set(out, "params", column(estimates));
  set(out, "bse", column(errors));
}

// Whether `value` is a result of momentid_identify (or select): a struct with params and
// param_names.
bool identify_result(const mxArray* value) {
  return mxIsStruct(value) && mxGetNumberOfElements(value) == 1 &&
         mxGetField(value, 0, "params") != nullptr &&
         mxGetField(value, 0, "param_names") != nullptr;
}

// Parameter values from a struct of numbers, or from an identify result (its estimates).
ParameterValues parameter_values(const Model& model, const mxArray* value) {
  std::vector<std::string> items;
  if (value != nullptr) {
    const mxArray* from = value;
    if (identify_result(value)) {
      const mxArray* names = mxGetField(value, 0, "param_names");
      const mxArray* numbers = mxGetField(value, 0, "params");
      const std::vector<std::string> list = names_of(names, "params.param_names");
      if (!mxIsDouble(numbers) || mxGetNumberOfElements(numbers) != list.size()) {
        throw UsageError("params", "expected a result's params, one per param_names entry");
      }
      for (std::size_t i = 0; i < list.size(); ++i) {
        items.push_back(list[i] + "=" + option_number_text(mxGetPr(numbers)[i]));
      }
      from = nullptr;
    }
    if (from != nullptr) {
      for (const auto& [name, text] : pair_list(from, "params")) items.push_back(name + "=" + text);
    }
  }
  return parse_parameter_values(model, items);
}

// The warnings of a call, which momentid_call issues as Octave's.
std::vector<std::string> warnings;

void warn_each(const std::vector<std::string>& given) {
  warnings.insert(warnings.end(), given.begin(), given.end());
}

// --- commands -------------------------------------------------------------------------------

mxArray* derive_command(const Model& model, Arguments& args) {
  const mxArray* lags = args.take("lags");
  const mxArray* instruments = args.take("instruments");
  const mxArray* measured = args.take("measured");
  const mxArray* multipliers = args.take("multipliers");
  const std::optional<std::int64_t> degree = optional_count(args, "degree", kMostInt);
  args.finish({"lags", "instruments", "measured", "multipliers", "degree"});
  if (lags != nullptr) {
    LagOptions options;
    std::tie(options.first_lag, options.last_lag) = parse_lag_range(
        mxIsChar(lags) ? text(lags, "lags") : joined(lags, "lags", "..", "[FIRST LAST]"), "lags");
    if (instruments != nullptr) {
      options.instruments = parse_instrument_list(
          model, joined(instruments, "instruments", ",", "names"), "instruments");
    }
    if (measured != nullptr) {
      std::vector<bool> flags(model.variables().size(), false);
      for (const std::string& name : names_of(measured, "measured")) {
        const int v = model.variable_index(name);
        if (v < 0)
          throw UsageError("measured", "'" + name + "' is not a state or input of the model");
        flags[static_cast<std::size_t>(v)] = true;
      }
      options.measured = flags;
    }
    const LaggedSystem system = derive_lagged(model, options);
    mxArray* out = result(json_value(system), format_text(system));
    set(out, "latex", mxCreateString(format_latex(system).c_str()));
    return out;
  }
  DeriveOptions options;
  if (multipliers != nullptr) {
    options.multipliers = parse_multiplier_list(
        model, joined(multipliers, "multipliers", ", ", "monomials"), "multipliers");
  }
  if (degree) options.degree = static_cast<int>(*degree);  // at most kMostInt
  const MomentSystem system = derive(model, options);
  mxArray* out = result(json_value(system), format_text(system));
  set(out, "latex", mxCreateString(format_latex(system).c_str()));
  return out;
}

// An option of identify's and select's as the text its setter reads (see OptionValue).
std::optional<std::string> option_text(const OptionDescription& o, const mxArray* value) {
  const std::string name(o.keyword);
  const bool list = o.value == OptionValue::kNames || o.value == OptionValue::kMonomials ||
                    o.value == OptionValue::kPairs;
  if (mxIsChar(value) && o.value != OptionValue::kSwitch && !list) return text(value, name);
  std::string out;
  switch (o.value) {
    case OptionValue::kCount:
      return std::to_string(
          whole(value, name, 0, std::int64_t{1} << 53, "a whole number, 0 or more"));
    case OptionValue::kWhole:
      return std::to_string(
          whole(value, name, -(std::int64_t{1} << 53), std::int64_t{1} << 53, "a whole number"));
    case OptionValue::kNumber:
      return option_number_text(number(value, name));
    case OptionValue::kText:
    case OptionValue::kChoice:
    case OptionValue::kRecord:
      return text(value, name);
    case OptionValue::kSwitch:
      if (!truth(value, name)) return std::nullopt;
      return std::string(o.value_name);
    case OptionValue::kSize:
      return std::to_string(whole(value, name, 0, std::int64_t{1} << 53, "a size in bytes"));
    case OptionValue::kRange: {
      const std::vector<double> ends = numbers_of(value, name, "[FIRST LAST]");
      if (ends.size() != 2) {
        throw UsageError(name, "expected [FIRST LAST], found " + describe(value));
      }
      return joined(value, name, "..", "[FIRST LAST]");
    }
    case OptionValue::kNames:
      out = joined(value, name, ",", "a name or a cell array of names");
      break;
    case OptionValue::kMonomials:
      out = joined(value, name, ", ", "monomials, in a cell array or one string");
      break;
    case OptionValue::kPairs:
      out = pairs(value, name);
      break;
  }
  if (!out.empty()) return out;
  if (!o.when_empty.empty()) return std::string(o.when_empty);
  return std::nullopt;
}

// identify's or select's options through the option table; the model completed by the
// columns of states' derivatives.
Model table_options(const Model& model, const DataSource& source, Arguments& args,
                    const std::string& command, SelectOptions& into) {
  std::vector<GivenOption> given;
  std::vector<std::string> known;
  for (const OptionDescription* o : options_of(command)) {
    const std::string keyword(o->keyword);
    known.push_back(keyword);
    const mxArray* value = args.take(keyword);
    if (value == nullptr) continue;
    if (std::optional<std::string> text = option_text(*o, value)) {
      given.push_back({o, std::move(*text), keyword});
    }
  }
  if (command == "select") {
    known.push_back("validation");
    args.take("validation");  // read by the caller
  }
  args.finish(known);
  Model completed = apply_options(given, model, source, into);
  check_interrupt(into.identify.record.control);
  return completed;
}

mxArray* identify_command(const Model& model, const DataSource& source, Arguments& args) {
  SelectOptions with;
  const Model completed = table_options(model, source, args, "identify", with);
  const IdentifyResult r = identify(completed, source, with.identify);
  const nlohmann::ordered_json value = json_value(r);
  mxArray* out = result(value, format_text(r));
  add_vectors(out, value["parameters"]);
  return out;
}

mxArray* select_command(const Model& model, const DataSource& source, Arguments& args,
                        std::vector<std::vector<double>>& copies) {
  SelectOptions with;
  const mxArray* validation = args.take("validation");
  const Model completed = table_options(model, source, args, "select", with);
  if (validation != nullptr) with.validation = data_source(validation, "validation", copies);
  const SelectResult r = select_terms(completed, source, with);
  const nlohmann::ordered_json value = json_value(r);
  mxArray* out = result(value, format_text(r));
  add_vectors(out, value["parameters"]);
  set(out, "model_text", mxCreateString(chosen_model_text(r).c_str()));
  return out;
}

mxArray* check_command(const mxArray* model, const DataSource& source, Arguments& args) {
  CheckOptions with;
  if (auto lags = optional_count(args, "lags")) with.lags = static_cast<std::size_t>(*lags);
  with.record = record_options(args);
  std::vector<std::string> known = kRecordNames;
  known.insert(known.begin(), "lags");
  args.finish(known);
  std::optional<Model> completed;
  if (model != nullptr && !mxIsEmpty(model)) {
    completed = declare_derivative_columns(model_of(model), with.record, source);
  }
  const CheckResult r = check(source, completed ? &*completed : nullptr, with);
  return result(json_value(r), format_text(r));
}

// What validate compared, as struct fields of column vectors: t, run ([] for one run),
// simulated, measured and inputs (a field per variable), compared (rows past each run's skip).
mxArray* validate_series(const ValidateResult& r) {
  const Model& model = *r.model;
  const Record& record = r.replay.record;
  mxArray* simulated = mxCreateStructMatrix(1, 1, 0, nullptr);
  for (std::size_t j = 0; j < model.states().size(); ++j) {
    set(simulated, variable_field(model.states()[j].name, {}),
        column(series_simulated(r.replay, j)));
  }
  mxArray* measured = mxCreateStructMatrix(1, 1, 0, nullptr);
  for (const OutputFit& output : r.outputs) {
    if (!valid_field_name(output.name)) continue;  // y'': in the JSON's outputs
    set(measured, output.name.c_str(),
        column(series_recorded(record, output_variable(model, output.state))));
  }
  mxArray* inputs = mxCreateStructMatrix(1, 1, 0, nullptr);
  const std::size_t states = model.states().size();
  for (std::size_t v = states; v < states + model.inputs().size(); ++v) {
    set(inputs, variable_field(model.variables()[v].name, {}), column(series_recorded(record, v)));
  }
  std::vector<bool> past;
  for (std::size_t k = 0; k < record.runs.size(); ++k) {
    for (std::size_t n = 0; n < record.runs[k].rows(); ++n) past.push_back(n >= r.skip[k]);
  }
  mxArray* compared = mxCreateLogicalMatrix(past.size(), 1);
  std::copy(past.begin(), past.end(), mxGetLogicals(compared));
  mxArray* out = mxCreateStructMatrix(1, 1, 0, nullptr);
  set(out, "t", column(series_times(record)));
  set(out, "run",
      record.runs.size() > 1 ? column(series_runs(record)) : mxCreateDoubleMatrix(0, 0, mxREAL));
  set(out, "simulated", simulated);
  set(out, "measured", measured);
  set(out, "inputs", inputs);
  set(out, "compared", compared);
  return out;
}

mxArray* validate_command(const Model& model, const DataSource& source, Arguments& args) {
  ValidateOptions with;
  const mxArray* params = args.take("params");
  with.replay.parameters = parameter_values(model, params);
  with.replay.record = record_options(args);
  if (auto substeps = optional_count(args, "substeps", kMostInt)) {
    with.replay.substeps = static_cast<int>(*substeps);
  }
  if (auto method = optional_text(args, "interpolation")) {
    with.replay.interpolation = parse_interpolation(*method, "interpolation");
  }
  if (auto skip = optional_count(args, "skip")) with.skip = static_cast<std::size_t>(*skip);
  if (auto lags = optional_count(args, "lags", kMostInt)) with.lags = static_cast<int>(*lags);
  if (const mxArray* center = args.take("center")) with.center = names_of(center, "center");
  const std::optional<std::string> plot = optional_text(args, "plot");
  std::vector<std::string> known = kRecordNames;
  known.insert(known.begin(),
               {"params", "substeps", "interpolation", "skip", "lags", "center", "plot"});
  args.finish(known);
  const Model completed = declare_derivative_columns(model, with.replay.record, source);
  ValidateResult r = validate(completed, source, with);
  r.parameters_from = params == nullptr         ? "the model's nominal values"
                      : identify_result(params) ? "the estimates of momentid_identify"
                                                : "the model's nominal values and params";
  if (plot) write_plot(r, *plot);
  mxArray* out = result(json_value(r), format_text(r));
  set(out, "series", validate_series(r));
  return out;
}

mxArray* simulate_command(const Model& model, Arguments& args) {
  SimulationOptions options;
  options.parameters = parameter_values(model, args.take("params"));
  std::vector<std::pair<std::string, std::string>> inputs;
  if (const mxArray* v = args.take("inputs")) inputs = pair_list(v, "inputs");
  for (const auto& given : inputs) {
    const auto& declared = model.inputs();
    if (std::none_of(declared.begin(), declared.end(),
                     [&](const Declaration& d) { return d.name == given.first; })) {
      throw UsageError("inputs", "'" + given.first + "' is not an input of model " + model.name());
    }
  }
  for (const Declaration& input : model.inputs()) {
    std::string spec = "ma:K=10,w=0.1";  // as --input: the default process
    for (const auto& [name, given] : inputs) {
      if (name == input.name) spec = given;
    }
    options.inputs.push_back(InputSpec::parse(spec, "inputs." + input.name));
  }
  if (auto dt = optional_number(args, "dt")) options.dt = *dt;
  if (auto samples = optional_count(args, "samples"))
    options.samples = static_cast<std::size_t>(*samples);
  if (auto burn_in = optional_count(args, "burn_in"))
    options.burn_in = static_cast<std::size_t>(*burn_in);
  if (auto runs = optional_count(args, "runs")) options.runs = static_cast<std::size_t>(*runs);
  if (auto seed = optional_count(args, "seed")) options.seed = static_cast<std::uint64_t>(*seed);
  if (const mxArray* v = args.take("noise")) {
    for (const auto& [channel, level] : pair_list(v, "noise")) {
      options.noise.push_back({channel, parse_option_number(level, "noise")});
    }
  }
  if (const mxArray* v = args.take("observe")) options.observe = names_of(v, "observe");
  const std::optional<std::string> path = optional_text(args, "path");
  const std::optional<std::string> format = optional_text(args, "format");
  args.finish({"params", "inputs", "dt", "samples", "burn_in", "runs", "seed", "noise", "observe",
               "path", "format"});
  if (path) {
    const FileFormat written = simulation_format(
        *path, format ? std::optional(parse_file_format(*format, "format")) : std::nullopt,
        "format", "path");
    warn_each(simulate_to_file(model, options, *path, written));
    return mxCreateString(path->c_str());
  }
  options.validate(model);
  const std::vector<std::size_t> channels = observed_channels(model, options);
  const std::size_t rows = options.samples * options.runs;
  mxArray* out = mxCreateStructMatrix(1, 1, 0, nullptr);
  mxArray* time = mxCreateDoubleMatrix(rows, 1, mxREAL);
  set(out, "t", time);
  std::vector<double*> columns;
  for (std::size_t c : channels) {
    mxArray* values = mxCreateDoubleMatrix(rows, 1, mxREAL);
    columns.push_back(mxGetPr(values));
    set(out, variable_field(model.variables()[c].name, {"t", "run", "metadata"}), values);
  }
  double* run = nullptr;
  if (options.runs > 1) {
    mxArray* runs = mxCreateDoubleMatrix(rows, 1, mxREAL);
    run = mxGetPr(runs);
    set(out, "run", runs);
  }
  ArraySink sink(columns, channels, mxGetPr(time), run, options.samples);
  const std::vector<double> noise_sd = noise_standard_deviations(model, options);
  StepCheck check(model, options, sink);
  simulate(model, options, check, noise_sd);
  if (const std::optional<std::string> warning = check.warning()) warn_each({*warning});
  // The metadata a file would carry, '-' and '.' written '_' (input_hold, param_k).
  mxArray* metadata = mxCreateStructMatrix(1, 1, 0, nullptr);
  const DataMetadata written = simulation_metadata(model, options, noise_sd);
  for (const DataMetadata::Line& line : written.lines()) {
    for (auto [key, value] : line) {
      std::replace(key.begin(), key.end(), '-', '_');
      std::replace(key.begin(), key.end(), '.', '_');
      if (valid_field_name(key)) set(metadata, key.c_str(), mxCreateString(value.c_str()));
    }
  }
  set(out, "metadata", metadata);
  return out;
}

// Runs `command` on the arguments after it.
mxArray* run(const std::string& command, int count, const mxArray* const* values) {
  const std::string function = "momentid_" + command;
  if (command == "derive" || command == "simulate") {
    if (count < 1) throw UsageError(function + ": expected a model");
    Arguments args(count - 1, values + 1, function);
    const Model model = model_of(values[0]);
    return command == "derive" ? derive_command(model, args) : simulate_command(model, args);
  }
  if (command != "identify" && command != "select" && command != "check" && command != "validate") {
    throw UsageError("momentid_mex: unknown command '" + command + "'");
  }
  if (count < 3) throw UsageError(function + ": expected a model and data");
  const std::string name = text(values[2], "data name");
  Arguments args(count - 3, values + 3, function);
  std::vector<std::vector<double>> copies;
  const DataSource source = data_source(values[1], name.empty() ? "<struct>" : name, copies);
  if (command == "check") return check_command(values[0], source, args);
  const Model model = model_of(values[0]);
  if (command == "identify") return identify_command(model, source, args);
  if (command == "select") return select_command(model, source, args, copies);
  return validate_command(model, source, args);
}

// The name a message gives the options field `field`: its keyword here ("fixed" is `fix`).
std::string keyword_of(const std::string& field) {
  if (field == "parameters") return "params";
  if (const OptionDescription* option = option_of_field(field)) return std::string(option->keyword);
  return field;
}

}  // namespace
}  // namespace momentid::mex

// [RESULT, ID, MESSAGE, WARNINGS] = momentid_mex(COMMAND, ...): the error, if any, as its
// identifier and message (empty without one), which momentid_call raises, and the warnings (a
// cell column), which it issues. An error raised here would leave the call without unwinding it
// (MATLAB), and Octave puts the gateway's name in front of its messages.
void mexFunction(int nlhs, mxArray* plhs[], int nrhs, const mxArray* prhs[]) {
  using namespace momentid;
  using momentid::mex::keyword_of;
  std::string id, message;
  mxArray* out = nullptr;
  bool interrupted = false;
  mex::warnings.clear();
  try {
    if (nrhs < 1 || !mxIsChar(prhs[0])) throw UsageError("momentid_mex: expected a command");
    out = mex::run(mex::text(prhs[0], "command"), nrhs - 1, prhs + 1);
  } catch (const Interrupted&) {
    interrupted = true;
    id = "momentid:interrupted";
    message = "interrupted";
  } catch (const ParseError& e) {
    id = "momentid:parse";
    message = render_with_caret(e, keyword_of);
  } catch (const ModelError& e) {
    id = "momentid:model";
    message = render_with_caret(e, keyword_of);
  } catch (const DataError& e) {
    id = "momentid:data";
    message = render_with_caret(e, keyword_of);
  } catch (const UsageError& e) {
    id = "momentid:usage";
    message = e.text(keyword_of);
  } catch (const Error& e) {
    id = "momentid:error";
    message = e.what();
  } catch (const std::bad_alloc&) {
    id = "momentid:memory";
    message = "out of memory";
  } catch (const std::exception& e) {
    id = "momentid:internal";
    message = e.what();
  } catch (...) {
    id = "momentid:internal";
    message = "an unknown exception";
  }
#if defined(HAVE_OCTAVE)
  // Ctrl-C ends the call as it ends any of Octave's own.
  if (interrupted) octave_quit();
#else
  (void)interrupted;
#endif
  plhs[0] = out != nullptr ? out : mxCreateDoubleMatrix(0, 0, mxREAL);
  if (nlhs > 1) plhs[1] = mxCreateString(id.c_str());
  if (nlhs > 2) plhs[2] = mxCreateString(message.c_str());
  if (nlhs > 3) plhs[3] = mex::strings(mex::warnings);
}
