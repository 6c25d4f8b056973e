// The compiled part of the Python module `momentid` (python/momentid/__init__.py is the rest):
// thin functions over the library that take and return Python objects. The arrays of a record
// are read in place (DataSource::memory), and the GIL is released while the library works.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "arrays.hpp"
#include "json_value.hpp"
#include "momentid/convert.hpp"
#include "momentid/momentid.hpp"
#include "options.hpp"

namespace py = pybind11;

namespace momentid::python {
namespace {

// Sets the module's exception for `kind` (a class of momentid/__init__.py) with the message
// and, for a located error, its place, as an exception translator must.
void raise(const char* kind, const std::string& message, const SourceLocation* where = nullptr) {
  py::object type = py::module_::import("momentid").attr(kind);
  py::object error = type(message);
  if (where != nullptr) {
    error.attr("file") = where->file;
    error.attr("line") = where->line;
    error.attr("column") = where->column;
    error.attr("source_line") = where->text;
  }
  PyErr_SetObject(type.ptr(), error.ptr());
}

// The keyword argument that sets the options field `field` (UsageError::option()): the keyword
// of option_table()'s entry for the field ("fixed" is `fix`), else the field itself ("dt").
std::string keyword_of(const std::string& field) {
  if (field == "parameters") return "params";
  if (const OptionDescription* option = option_of_field(field)) return std::string(option->keyword);
  return field;
}

void translate(std::exception_ptr thrown) {
  try {
    if (thrown) std::rethrow_exception(thrown);
  } catch (const Interrupted&) {
    // The signal's handler has set its exception (KeyboardInterrupt) already.
    if (PyErr_Occurred() == nullptr) PyErr_SetNone(PyExc_KeyboardInterrupt);
  } catch (const DataError& e) {
    raise("DataError", e.text(keyword_of), &e.location());
  } catch (const LocatedError& e) {  // ParseError, ModelError
    raise("ModelError", e.text(keyword_of), &e.location());
  } catch (const UsageError& e) {
    raise("UsageError", e.text(keyword_of));
  } catch (const Error& e) {
    raise("Error", e.what());
  }
}

// What a value of type T is, for messages.
template <class T>
const char* describe() {
  if constexpr (std::is_same_v<T, bool>) {
    return "True or False";
  } else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>) {
    return "a whole number, 0 or more";
  } else if constexpr (std::is_integral_v<T>) {
    return "a whole number";
  } else if constexpr (std::is_floating_point_v<T>) {
    return "a number";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "a string";
  } else {
    return "of the type documented";
  }
}

// Option `key` as T, nullopt when absent or None; UsageError when it is not a T.
template <class T>
std::optional<T> get(const py::dict& options, const char* key) {
  if (!options.contains(key) || options[key].is_none()) return std::nullopt;
  try {
    return options[key].cast<T>();
  } catch (const py::cast_error&) {
    throw UsageError(std::string(key) + ": expected " + describe<T>() + ", found " +
                     py::repr(options[key]).cast<std::string>());
  }
}

FileLayout layout_of(const py::dict& options) {
  FileLayout layout;
  if (auto rows = get<std::size_t>(options, "skip_rows")) layout.skip_rows = *rows;
  if (auto decimal = get<std::string>(options, "decimal")) {
    if (*decimal != "." && *decimal != ",") {
      throw UsageError("decimal: expected '.' or ',', found '" + *decimal + "'");
    }
    layout.decimal = (*decimal)[0];
  }
  if (auto names = get<std::vector<std::string>>(options, "names")) layout.column_names = *names;
  layout.dt_from = get<std::string>(options, "dt_from");
  if (auto missing = get<std::string>(options, "missing")) {
    layout.missing = parse_missing_values(*missing, "missing");
  }
  return layout;
}

std::optional<InputHold> hold_of(const py::dict& options) {
  const auto hold = get<std::string>(options, "input_hold");
  if (!hold) return std::nullopt;
  return parse_input_hold(*hold, "hold");
}

// The keywords of RecordOptions: columns, dt, the layout's, input_hold and threads.
RecordOptions record_options(const py::dict& options) {
  RecordOptions out;
  if (auto columns = get<std::map<std::string, std::string>>(options, "columns")) {
    out.columns = *columns;
  }
  out.dt = get<double>(options, "dt");
  out.layout = layout_of(options);
  out.hold = hold_of(options);
  if (auto threads = get<std::size_t>(options, "threads")) out.control.threads = *threads;
  release_during_pass(out.control);
  return out;
}

// `NAME=VALUE` items, as --set and --fix take them, from a mapping of names to numbers.
std::vector<std::string> assignments(const std::map<std::string, py::object>& values) {
  std::vector<std::string> out;
  for (const auto& [name, value] : values) {
    out.push_back(name + "=" + py::str(value).cast<std::string>());
  }
  return out;
}

// The values of `options[key]` by name, each number kept as the decimal Python writes for it.
ParameterValues parameters_of(const Model& model, const py::dict& options, const char* key) {
  const auto values = get<std::map<std::string, py::object>>(options, key);
  return parse_parameter_values(model, values ? assignments(*values) : std::vector<std::string>{});
}

// --- derive ---------------------------------------------------------------------------------

struct Derivation {
  std::string text, latex;
  py::object json;  // the JSON value, converted
  std::size_t equations = 0;
};

Derivation derive_equations(const Model& model, const py::dict& options) {
  Derivation out;
  if (auto lags = get<std::pair<int, int>>(options, "lags")) {
    LagOptions lag_options;
    std::tie(lag_options.first_lag, lag_options.last_lag) = *lags;
    if (auto text = get<std::string>(options, "instruments")) {
      lag_options.instruments = parse_instrument_list(model, *text, "instruments");
    }
    if (auto measured = get<std::vector<std::string>>(options, "measured")) {
      std::vector<bool> flags(model.variables().size(), false);
      for (const std::string& name : *measured) {
        const int v = model.variable_index(name);
        if (v < 0)
          throw UsageError("measured: '" + name + "' is not a state or input of the model");
        flags[static_cast<std::size_t>(v)] = true;
      }
      lag_options.measured = flags;
    }
    const LaggedSystem system = derive_lagged(model, lag_options);
    return {format_text(system), format_latex(system), to_python(json_value(system)),
            system.equations.size()};
  }
  DeriveOptions derive_options;
  if (auto text = get<std::string>(options, "multipliers")) {
    derive_options.multipliers = parse_multiplier_list(model, *text, "multipliers");
  }
  if (auto degree = get<int>(options, "degree")) derive_options.degree = *degree;
  const MomentSystem system = derive(model, derive_options);
  return {format_text(system), format_latex(system), to_python(json_value(system)),
          system.equations.size()};
}

// --- identify and select -------------------------------------------------------------------

// The options of `command` set from `options` through the option table, against `model`
// completed by the columns of states' derivatives, which is returned.
Model set_options(const Model& model, const DataSource& source, const py::dict& options,
                  const std::string& command, SelectOptions& into) {
  Model completed = apply_options(given_options(options, command), model, source, into);
  release_during_pass(into.identify.record.control);
  return completed;
}

// --- simulate -------------------------------------------------------------------------------

SimulationOptions simulation_options(const Model& model, const py::dict& options) {
  SimulationOptions out;
  out.parameters = parameters_of(model, options, "params");
  std::vector<std::string> inputs;
  if (auto given = get<std::map<std::string, std::string>>(options, "inputs")) {
    for (const auto& [name, spec] : *given) inputs.push_back(name + "=" + spec);
  }
  // As `--input`: every input named, the rest at the default process.
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    const std::string& name = model.inputs()[i].name;
    std::string spec = "ma:K=10,w=0.1";
    for (const std::string& item : inputs) {
      if (item.starts_with(name + "=")) spec = item.substr(name.size() + 1);
    }
    out.inputs.push_back(InputSpec::parse(spec, "inputs['" + name + "']"));
  }
  for (const std::string& item : inputs) {
    const std::string name = item.substr(0, item.find('='));
    const auto& declared = model.inputs();
    if (std::none_of(declared.begin(), declared.end(),
                     [&](const Declaration& d) { return d.name == name; })) {
      throw UsageError("inputs: '" + name + "' is not an input of model " + model.name());
    }
  }
  if (auto dt = get<double>(options, "dt")) out.dt = *dt;
  if (auto samples = get<std::size_t>(options, "samples")) out.samples = *samples;
  if (auto burn_in = get<std::size_t>(options, "burn_in")) out.burn_in = *burn_in;
  if (auto runs = get<std::size_t>(options, "runs")) out.runs = *runs;
  if (auto seed = get<std::uint64_t>(options, "seed")) out.seed = *seed;
  if (auto noise = get<std::map<std::string, double>>(options, "noise")) {
    for (const auto& [channel, level] : *noise) out.noise.push_back({channel, level});
  }
  if (auto observe = get<std::vector<std::string>>(options, "observe")) out.observe = *observe;
  return out;
}

// The simulated record as {name: array} (t, the observed channels, run when there are several),
// its metadata as a file would carry it, and the warnings; or, with `path`, the file written and
// the warnings.
py::tuple simulate_record(const Model& model, const py::dict& options) {
  const SimulationOptions simulation = simulation_options(model, options);
  if (auto path = get<std::string>(options, "path")) {
    const std::optional<std::string> asked = get<std::string>(options, "format");
    const FileFormat format = simulation_format(
        *path, asked ? std::optional(parse_file_format(*asked, "format")) : std::nullopt, "format",
        "path");
    return py::make_tuple(py::none(), py::none(),
                          simulate_to_file(model, simulation, *path, format));
  }
  simulation.validate(model);
  const std::vector<std::size_t> channels = observed_channels(model, simulation);
  const auto rows = static_cast<py::ssize_t>(simulation.samples * simulation.runs);
  py::dict out;
  py::array_t<double> time(rows);
  out["t"] = time;
  std::vector<double*> columns;
  for (std::size_t c : channels) {
    py::array_t<double> column(rows);
    columns.push_back(column.mutable_data());
    out[py::str(model.variables()[c].name)] = column;
  }
  double* run = nullptr;
  if (simulation.runs > 1) {
    py::array_t<double> runs(rows);
    run = runs.mutable_data();
    out["run"] = runs;
  }
  ArraySink sink(columns, channels, time.mutable_data(), run, simulation.samples);
  const std::vector<double> noise_sd = noise_standard_deviations(model, simulation);
  StepCheck check(model, simulation, sink);
  simulate(model, simulation, check, noise_sd);
  const std::optional<std::string> warning = check.warning();
  std::vector<std::string> warnings;
  if (warning) warnings.push_back(*warning);
  py::dict metadata;
  const DataMetadata written = simulation_metadata(model, simulation, noise_sd);
  for (const DataMetadata::Line& line : written.lines()) {
    for (const auto& [key, value] : line) metadata[py::str(key)] = value;
  }
  return py::make_tuple(out, metadata, warnings);
}

// --- validate -------------------------------------------------------------------------------

ValidateOptions validate_options(const Model& model, const py::dict& options) {
  ValidateOptions out;
  out.replay.parameters = parameters_of(model, options, "params");
  out.replay.record = record_options(options);
  if (auto substeps = get<int>(options, "substeps")) out.replay.substeps = *substeps;
  if (auto method = get<std::string>(options, "interpolation")) {
    out.replay.interpolation = parse_interpolation(*method, "interpolation");
  }
  out.skip = get<std::size_t>(options, "skip");
  if (auto lags = get<int>(options, "lags")) out.lags = *lags;
  if (auto center = get<std::vector<std::string>>(options, "center")) out.center = *center;
  // An IdentifyResult's covariance; None is an unknown error, as null in the file.
  if (auto covariance =
          get<std::vector<std::vector<std::optional<double>>>>(options, "covariance")) {
    for (const auto& row : *covariance) {
      std::vector<double>& values = out.covariance.emplace_back();
      for (const auto& entry : row) values.push_back(entry.value_or(NAN));
    }
  }
  return out;
}

// The model's response to a record's inputs (replay_columns) and the metadata; or, with
// `path`, the file written (as simulate --input-file writes it).
py::tuple replay_record(const Model& model, const DataSource& source, const py::dict& options) {
  const ValidateOptions with = validate_options(model, options);
  const std::optional<std::string> path = get<std::string>(options, "path");
  std::optional<FileFormat> format;
  if (path) {
    const std::optional<std::string> asked = get<std::string>(options, "format");
    format = simulation_format(
        *path, asked ? std::optional(parse_file_format(*asked, "format")) : std::nullopt, "format",
        "path");
  }
  const std::optional<Replay> done = replay(model, source, with.replay);
  if (path) {
    return py::make_tuple(py::none(), py::none(), write_replay(model, *done, *path, *format));
  }
  // What the record says of its sampling holds for the response too; its parameters do not.
  py::dict metadata;
  metadata["dt"] = py::str(py::repr(py::float_(done->record.dt)));
  if (auto hold = done->record.metadata.get("input-hold")) metadata["input-hold"] = *hold;
  return py::make_tuple(replay_columns(model, *done), metadata, std::vector<std::string>{});
}

}  // namespace
}  // namespace momentid::python

PYBIND11_MODULE(_momentid, m) {
  using namespace momentid;
  using namespace momentid::python;
  m.doc() = "The compiled part of momentid; use the package `momentid`.";
  m.attr("__version__") = MOMENTID_VERSION;
  py::register_exception_translator(translate);

  py::class_<Model>(m, "Model")
      .def(py::init([](const std::string& text, const std::string& name) {
             return parse_model(text, name);
           }),
           py::arg("text"), py::arg("name") = "<string>")
      .def_static("_from_file", &parse_model_file, py::arg("path"))
      .def_property_readonly("name", &Model::name)
      .def_property_readonly("title", &Model::title)
      .def_property_readonly("states",
                             [](const Model& model) {
                               std::vector<std::string> out;
                               for (const auto& d : model.states()) out.push_back(d.name);
                               return out;
                             })
      .def_property_readonly("inputs",
                             [](const Model& model) {
                               std::vector<std::string> out;
                               for (const auto& d : model.inputs()) out.push_back(d.name);
                               return out;
                             })
      .def_property_readonly("parameters",
                             [](const Model& model) {
                               std::vector<std::string> out;
                               for (const auto& d : model.parameters()) out.push_back(d.name);
                               return out;
                             })
      .def_property_readonly("nominal",
                             [](const Model& model) {
                               py::dict out;
                               for (const auto& d : model.parameters()) {
                                 out[py::str(d.name)] =
                                     d.value ? py::cast(d.value->to_double()) : py::none();
                               }
                               return out;
                             })
      .def_property_readonly("fixed", [](const Model& model) {
        std::vector<std::string> out;
        for (const auto& d : model.parameters()) {
          if (d.fixed) out.push_back(d.name);
        }
        return out;
      });

  m.def("_derive", [](const Model& model, const py::dict& options) {
    const Derivation d = derive_equations(model, options);
    return py::make_tuple(d.text, d.latex, d.json, d.equations);
  });

  m.def("_options", &option_list, py::arg("command"));

  m.def("_identify",
        [](const Model& model, const py::object& data, const std::string& name,
           const std::map<std::string, std::string>& metadata, const py::dict& options) {
          const DataSource source = data_source(data, name, metadata);
          SelectOptions with;
          const Model completed = set_options(model, source, options, "identify", with);
          const IdentifyResult result = identify(completed, source, with.identify);
          return py::make_tuple(format_text(result), to_python(json_value(result)));
        });

  m.def("_select", [](const Model& model, const py::object& data, const std::string& name,
                      const std::map<std::string, std::string>& metadata, const py::dict& options,
                      const py::object& validation, const std::string& validation_name,
                      const std::map<std::string, std::string>& validation_metadata) {
    const DataSource source = data_source(data, name, metadata);
    SelectOptions with;
    const Model completed = set_options(model, source, options, "select", with);
    if (!validation.is_none()) {
      with.validation = data_source(validation, validation_name, validation_metadata);
    }
    const SelectResult result = select_terms(completed, source, with);
    return py::make_tuple(format_text(result), to_python(json_value(result)),
                          chosen_model_text(result));
  });

  m.def("_check", [](const py::object& model, const py::object& data, const std::string& name,
                     const std::map<std::string, std::string>& metadata, const py::dict& options) {
    CheckOptions check_with;
    if (auto lags = get<std::size_t>(options, "lags")) check_with.lags = *lags;
    check_with.record = record_options(options);
    const DataSource source = data_source(data, name, metadata);
    std::optional<Model> with;
    if (!model.is_none()) {
      with = declare_derivative_columns(model.cast<const Model&>(), check_with.record, source);
    }
    const CheckResult result = check(source, with ? &*with : nullptr, check_with);
    return py::make_tuple(format_text(result), to_python(json_value(result)));
  });

  m.def("_simulate", &simulate_record);

  m.def("_replay", [](const Model& model, const py::object& data, const std::string& name,
                      const std::map<std::string, std::string>& metadata, const py::dict& options) {
    return replay_record(model, data_source(data, name, metadata), options);
  });

  m.def("_validate",
        [](const Model& model, const py::object& data, const std::string& name,
           const std::map<std::string, std::string>& metadata, const py::dict& options) {
          ValidateOptions validate_with = validate_options(model, options);
          const DataSource source = data_source(data, name, metadata);
          const Model with = declare_derivative_columns(model, validate_with.replay.record, source);
          ValidateResult result = validate(with, source, validate_with);
          result.parameters_from =
              get<std::string>(options, "parameters_from").value_or("the model's nominal values");
          if (auto plot = get<std::string>(options, "plot")) write_plot(result, *plot);
          return py::make_tuple(format_text(result), to_python(json_value(result)),
                                validate_series(result));
        });

  // Student's t law, as the library's intervals take it: the q-quantile and P(T > x).
  m.def("_t_quantile", [](double q, double dof) {
    return boost::math::quantile(boost::math::students_t(dof), q);
  });
  m.def("_t_upper_tail", [](double x, double dof) {
    return boost::math::cdf(boost::math::complement(boost::math::students_t(dof), x));
  });
}
