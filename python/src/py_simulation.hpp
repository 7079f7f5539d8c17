// seiche.Simulation: a scene being stepped from Python, and its particle columns as NumPy arrays
// without a copy.
//
// The columns are the store's own buffers (structure of arrays, one buffer per column), handed
// out as read-only 1-D views (writeable=False). A view is valid until the next step(): each
// substep's neighbor sort reorders the store, which swaps every column with a spare buffer, so
// after a step an old view shows another column's or stale values, and the particle at index i
// is another particle (ids say which). The memory itself stays allocated while the view exists:
// every view keeps its Simulation alive (the view's base object), so reading a stale view is
// wrong but never a crash. Positions are offered as the three views (x, y, z), not as an (N, 3)
// array: the columns lie in separate buffers, so an (N, 3) array could only be a copy
// (numpy.stack(sim.positions, axis=1) makes one).
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "run/run_report.hpp"
#include "seiche/frame_exporter.hpp"
#include "seiche/simulation.hpp"

namespace seiche_py {

class PySimulation {
 public:
  /// Builds the simulation on `threads` threads (0: every core).
  PySimulation(const seiche::SceneDef& scene, int threads);

  /// Steps `frames` frames with the GIL released; between frames a pending Ctrl-C (or another
  /// Python signal) stops the loop. Throws seiche::SimulationError when a frame holds NaN or inf
  /// (the report records it), as `seiche run` does.
  void step(int frames);

  const seiche::Simulation& simulation() const { return *sim_; }
  int threads() const { return threads_; }
  /// The run report of the frames stepped so far (the JSON of `seiche run --report`).
  std::string report() const;
  /// Writes the current frame's files into `dir` as `seiche run` does: particles.%04d.ply and
  /// every cloth's OBJ. Returns the paths written.
  std::vector<std::string> write_frame(const std::filesystem::path& dir) const;

  /// A read-only NumPy view of column `name`, its base `owner` (the Python Simulation).
  pybind11::array column(const std::string& name, const pybind11::object& owner) const;
  /// The names of the columns that hold values now (built-ins, the families', enabled scratch).
  std::vector<std::string> column_names() const;

 private:
  int threads_;
  std::unique_ptr<seiche::Simulation> sim_;
  std::vector<std::unique_ptr<seiche::FrameExporter>> exporters_;  ///< the families' (cloth OBJ)
  std::unique_ptr<seiche::RunReport> report_;
  std::mutex stepping_;  ///< one step at a time (the GIL is released while stepping)
};

/// Adds the class seiche.Simulation to `module`.
void register_simulation(pybind11::module_& module);

}  // namespace seiche_py
