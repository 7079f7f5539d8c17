// The command line's three commands as Python functions (seiche.run, seiche.bake, seiche.bench):
// the same library calls as apps/seiche, the same files, the same errors; the results as
// dicts. The GIL is released while they simulate.
#pragma once

#include <pybind11/pybind11.h>

namespace seiche_py {

/// Adds _seiche.run, _seiche.bake and _seiche.bench to `module` (python/seiche/__init__.py
/// wraps them with their documented signatures).
void register_commands(pybind11::module_& module);

}  // namespace seiche_py
