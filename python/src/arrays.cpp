#include "arrays.hpp"

namespace py = pybind11;

namespace momentid::python {
namespace {

py::array_t<double> array(const std::vector<double>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(values.size()), values.data());
}

}  // namespace

DataSource data_source(const py::object& data, const std::string& name,
                       const std::map<std::string, std::string>& metadata) {
  if (py::isinstance<py::str>(data)) return DataSource::file(data.cast<std::string>());
  const auto items = data.cast<py::list>();
  if (!items.empty() && py::isinstance<py::str>(items[0])) {
    return DataSource::files(data.cast<std::vector<std::string>>());
  }
  MemoryData memory;
  memory.name = name;
  DataMetadata::Line line(metadata.begin(), metadata.end());
  if (!line.empty()) memory.metadata.add_line(std::move(line));
  bool first = true;
  for (const py::handle item : items) {
    const auto pair = item.cast<py::tuple>();
    const std::string column = pair[0].cast<std::string>();
    const auto array = pair[1].cast<py::array>();
    if (array.ndim() != 1 || !array.dtype().is(py::dtype::of<double>()) || array.strides(0) < 0 ||
        array.strides(0) % static_cast<py::ssize_t>(sizeof(double)) != 0) {
      throw UsageError("column '" + column +
                       "': expected a one-dimensional float64 array with a forward stride");
    }
    const auto rows = static_cast<std::size_t>(array.shape(0));
    if (first) {
      memory.rows = rows;
      first = false;
    } else if (rows != memory.rows) {
      throw UsageError("column '" + column + "' has " + std::to_string(rows) + " values, but '" +
                       memory.columns.front().name + "' has " + std::to_string(memory.rows) +
                       ": every column needs one value per sample");
    }
    memory.columns.push_back(
        {column, static_cast<const double*>(array.data()),
         static_cast<std::size_t>(array.strides(0) / static_cast<py::ssize_t>(sizeof(double)))});
  }
  if (first) throw UsageError("the data have no columns");
  return DataSource::memory(std::move(memory));
}

py::dict replay_columns(const Model& model, const Replay& done) {
  py::dict out;
  out["t"] = array(series_times(done.record));
  const std::size_t states = model.states().size();
  for (std::size_t j = 0; j < states; ++j)
    out[py::str(model.states()[j].name)] = array(series_simulated(done, j));
  for (std::size_t v = states; v < states + model.inputs().size(); ++v) {
    out[py::str(model.variables()[v].name)] = array(series_recorded(done.record, v));
  }
  if (done.record.runs.size() > 1) out["run"] = array(series_runs(done.record));
  return out;
}

py::dict validate_series(const ValidateResult& result) {
  const Model& model = *result.model;
  const Record& record = result.replay.record;
  py::dict states, measured, inputs;
  for (std::size_t j = 0; j < model.states().size(); ++j) {
    states[py::str(model.states()[j].name)] = array(series_simulated(result.replay, j));
  }
  for (const OutputFit& output : result.outputs) {
    measured[py::str(output.name)] =
        array(series_recorded(record, output_variable(model, output.state)));
  }
  for (std::size_t v = model.states().size(); v < model.states().size() + model.inputs().size();
       ++v) {
    inputs[py::str(model.variables()[v].name)] = array(series_recorded(record, v));
  }
  std::size_t rows = 0;
  for (const RecordRun& run : record.runs) rows += run.rows();
  py::array_t<bool> compared(static_cast<py::ssize_t>(rows));
  bool* into = compared.mutable_data();
  for (std::size_t r = 0; r < record.runs.size(); ++r) {
    for (std::size_t n = 0; n < record.runs[r].rows(); ++n) *into++ = n >= result.skip[r];
  }
  py::dict out;
  out["t"] = array(series_times(record));
  out["run"] = record.runs.size() > 1 ? py::object(array(series_runs(record))) : py::none();
  out["simulated"] = states;
  out["measured"] = measured;
  out["inputs"] = inputs;
  out["compared"] = compared;
  return out;
}

}  // namespace momentid::python
