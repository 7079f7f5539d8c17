// _seiche: the compiled half of the Python package `seiche` (python/seiche/__init__.py is the
// other): the Simulation class, the commands, the errors, and what the build is.
#include <pybind11/pybind11.h>

#include "commands.hpp"
#include "errors.hpp"
#include "py_simulation.hpp"
#include "seiche/kernels/simd_info.hpp"
#include "seiche/scene_loader.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_seiche, m) {
  m.doc() = "Seiche's engine, bound with pybind11 (use the package `seiche`)";
  m.attr("__version__") = SEICHE_VERSION;
  m.attr("simd") = seiche::kernels::simd_description();
  m.def("default_scene_json", [] { return std::string(seiche::default_scene_json()); },
        "The built-in dam break's JSON text.");
  seiche_py::register_errors(m);
  seiche_py::register_simulation(m);
  seiche_py::register_commands(m);
}
