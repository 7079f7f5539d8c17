#include "errors.hpp"

#include <string>

#include "seiche/bench.hpp"
#include "seiche/checkpoint.hpp"
#include "seiche/export/scene_exporters.hpp"
#include "seiche/output_files.hpp"
#include "seiche/runner.hpp"
#include "seiche/scene_loader.hpp"

namespace py = pybind11;

namespace seiche_py {

namespace {

// The classes, created once by register_errors (module lifetime: never freed).
PyObject* g_error = nullptr;
PyObject* g_input_error = nullptr;
PyObject* g_scene_error = nullptr;
PyObject* g_output_error = nullptr;
PyObject* g_simulation_error = nullptr;

// A new exception class `module`.<name> with these bases and exit_code, added to the module.
PyObject* make_class(py::module_& module, const char* name, py::tuple bases, int exit_code, const char* doc) {
  const std::string qualified = std::string("seiche.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (!type) throw py::error_already_set();
  py::handle(type).attr("exit_code") = exit_code;
  module.attr(name) = py::handle(type);
  return type;
}

// Raises `type` with `message` as its text; the extra attributes are set on the instance.
void set_python_error(PyObject* type, const char* message, py::dict attributes = {}) {
  py::object error = py::reinterpret_borrow<py::object>(type)(message);
  for (auto [key, value] : attributes) error.attr(key) = value;
  PyErr_SetObject(type, error.ptr());
}

}  // namespace

void register_errors(py::module_& m) {
  const py::handle exception(PyExc_Exception), value_error(PyExc_ValueError), os_error(PyExc_OSError),
      arithmetic_error(PyExc_ArithmeticError);
  g_error = make_class(m, "Error", py::make_tuple(exception), 1, "Any error of Seiche; str() is the CLI's message.");
  g_input_error = make_class(m, "InputError", py::make_tuple(py::handle(g_error), value_error), 2,
                             "Bad input: the CLI's exit code 2.");
  g_scene_error = make_class(m, "SceneError", py::make_tuple(py::handle(g_input_error)), 2,
                             "A bad scene value: .file, .json_path and .problem name it.");
  g_output_error = make_class(m, "OutputError", py::make_tuple(py::handle(g_error), os_error), 3,
                              "A file or folder could not be written: the CLI's exit code 3.");
  g_simulation_error = make_class(m, "SimulationError", py::make_tuple(py::handle(g_error), arithmetic_error), 4,
                                  "The simulation produced NaN or inf: the CLI's exit code 4.");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const seiche::SceneError& e) {
      py::dict attributes;
      attributes["file"] = e.file();
      attributes["json_path"] = e.json_path();
      attributes["problem"] = e.problem();
      set_python_error(g_scene_error, e.what(), attributes);
    } catch (const seiche::ResumeError& e) {
      set_python_error(g_input_error, e.what());
    } catch (const seiche::BenchError& e) {
      set_python_error(g_input_error, e.what());
    } catch (const seiche::ExportUnavailableError& e) {
      set_python_error(g_input_error, e.what());
    } catch (const seiche::IoError& e) {
      set_python_error(g_output_error, e.what());
    } catch (const seiche::SimulationError& e) {
      set_python_error(g_simulation_error, e.what());
    }
  });
}

void throw_input_error(const std::string& message) {
  set_python_error(g_input_error, message.c_str());
  throw py::error_already_set();
}

}  // namespace seiche_py
