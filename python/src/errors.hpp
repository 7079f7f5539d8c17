// Seiche's errors as Python exceptions, with the text the command line prints after
// "seiche: error: " and the exit code it would return:
//   seiche.Error            (Exception)                 exit_code 1: the base of all below
//   seiche.InputError       (Error, ValueError)         exit_code 2: bad input (a bench sweep, a
//                                                       checkpoint, output this build cannot write)
//   seiche.SceneError       (InputError)                exit_code 2: a scene value, with .file,
//                                                       .json_path and .problem
//   seiche.OutputError      (Error, OSError)            exit_code 3: a file or folder not writable
//   seiche.SimulationError  (Error, ArithmeticError)    exit_code 4: NaN or inf in the state
// Running out of memory is Python's MemoryError, as pybind11 maps it.
#pragma once

#include <pybind11/pybind11.h>

namespace seiche_py {

/// Creates the exception classes in `module` and registers the translation of Seiche's C++
/// exceptions into them.
void register_errors(pybind11::module_& module);

/// Raises seiche.InputError with `message` (an argument the Python API checks itself).
[[noreturn]] void throw_input_error(const std::string& message);

}  // namespace seiche_py
