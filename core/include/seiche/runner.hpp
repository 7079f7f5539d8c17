// Running a scene from start to end: step frames, write the particle files, show progress,
// collect the run report and print the summary. What `seiche run` does, callable from tests.
#pragma once

#include <filesystem>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "seiche/frame_metrics.hpp"
#include "seiche/pass_timer.hpp"
#include "seiche/scene.hpp"

namespace seiche {

struct RunOptions {
  std::filesystem::path out_dir;  ///< particle files go here; empty = write none
  int frames = 0;                 ///< 0 = the scene's output.frames
  int threads = 0;                ///< 0 = every core
  std::filesystem::path report;   ///< JSON run report; empty = none
  std::ostream* progress = nullptr;  ///< progress lines (stderr in the CLI); null = quiet
  std::ostream* summary = nullptr;   ///< settings, pass table and errors at the end
};

struct RunResult {
  int frames = 0;
  std::size_t particles = 0;
  int threads = 0;
  double wall_seconds = 0.0;
  std::vector<FrameMetrics> metrics;  ///< one per frame
  PassTimer timer;
  std::string report;  ///< the JSON run report (what RunOptions::report is written with)
};

/// The simulation produced NaN or inf. what() says in which frame and how many values.
class SimulationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws SimulationError naming `frame` when the frame's state holds NaN or inf.
void throw_if_diverged(const FrameMetrics& m, int frame);

/// Runs the scene. Throws IoError (output) or SimulationError (non-finite state); the run
/// report, if asked for, is written in every case, with the error in it.
RunResult run_scene(const SceneDef& scene, const RunOptions& options);

}  // namespace seiche
