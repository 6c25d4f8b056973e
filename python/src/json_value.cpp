#include "json_value.hpp"

#include <string>

namespace momentid::python {

namespace py = pybind11;

namespace {

// A byte that is not valid UTF-8 (a file name) becomes U+FFFD, as in the JSON text.
py::str text(const std::string& s) {
  PyObject* out = PyUnicode_DecodeUTF8(s.data(), static_cast<Py_ssize_t>(s.size()), "replace");
  if (out == nullptr) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(out);
}

}  // namespace

py::object to_python(const nlohmann::ordered_json& value) {
  using Type = nlohmann::ordered_json::value_t;
  switch (value.type()) {
    case Type::object: {
      py::dict out;
      for (const auto& [key, item] : value.items()) out[text(key)] = to_python(item);
      return out;
    }
    case Type::array: {
      py::list out;
      for (const auto& item : value) out.append(to_python(item));
      return out;
    }
    case Type::string:
      return text(value.get_ref<const std::string&>());
    case Type::boolean:
      return py::bool_(value.get<bool>());
    case Type::number_integer:
      return py::int_(value.get<std::int64_t>());
    case Type::number_unsigned:
      return py::int_(value.get<std::uint64_t>());
    case Type::number_float:
      return py::float_(value.get<double>());
    default:  // null, and the binary and discarded values that results never hold
      return py::none();
  }
}

}  // namespace momentid::python
