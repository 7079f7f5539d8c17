// `seiche bench SCENE --sweep ...`: what accuracy a setting buys and what it costs.
//
// The scene runs once for every combination of the swept values, then twice more: a reference
// run far past convergence, and the same reference with twice its substeps, whose difference
// to the reference says how far the reference itself can be trusted. Every run's error is the
// difference of its particle positions to the reference's, over every particle and every
// frame, in units of the particle spacing:
//   rms = sqrt(sum_f sum_i |x_i(f) - x_ref_i(f)|^2 / (frames particles)) / spacing
//   max = max_f max_i |x_i(f) - x_ref_i(f)| / spacing
// next to the constraint errors of the run report and the wall time per frame. The runs that
// no other run beats in both time and rms error form the Pareto front. A setting's time is the
// median of several runs after a warm-up (BenchRun::ms_per_frame), so that the order of the
// sweep does not move the front.
//
// The reference of a scene made only of cloth (isometric bending) and raw distance constraints,
// with no colliders and no contacts, is implicit Euler solved to convergence by Newton's method
// (implicit_euler.hpp); the reference of any other scene is XPBD at many substeps and
// iterations.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "seiche/frame_metrics.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// Bad bench arguments (a sweep that does not parse, a reference the scene cannot have).
class BenchError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One swept scene key and its values.
struct SweepAxis {
  std::string key;                  ///< JSON path, e.g. "solver.substeps"
  std::vector<std::string> values;  ///< JSON values, in sweep order
};

/// Parses "KEY=V1,V2,...". A key without a dot is a solver key: "substeps" is solver.substeps.
SweepAxis parse_sweep(std::string_view text);

enum class ReferenceKind { Auto, Xpbd, ImplicitEuler };

/// "auto", "xpbd" or "implicit" (--reference); throws BenchError for anything else.
ReferenceKind parse_reference_kind(std::string_view name);

struct BenchOptions {
  std::vector<SweepAxis> sweep;   ///< empty: substeps 1,2,4,8,16 x iterations 1,2,4,8
  int frames = 0;                 ///< 0: the scene's output.frames
  int threads = 0;                ///< 0: every core
  ReferenceKind reference = ReferenceKind::Auto;
  int reference_substeps = 0;     ///< 0: 4 x the largest swept substeps, at least 64
  int reference_iterations = 0;   ///< XPBD reference: 0 = 2 x the largest swept iterations, at least 16
  std::ostream* progress = nullptr;  ///< one line per run; null = quiet
};

struct BenchRun {
  enum class Role { Sweep, Reference, ReferenceCheck };
  Role role = Role::Sweep;
  std::vector<std::string> values;  ///< the swept values (one per axis; empty for the references)
  int substeps = 0;
  int iterations = 0;               ///< 0 for the implicit-Euler reference (Newton to convergence)
  /// Iterations per substep actually run, the mean over the run: above `iterations` when a
  /// density tolerance asked for more (0 for the implicit-Euler reference)
  double iterations_run = 0.0;
  int frames = 0;                   ///< frames completed
  bool diverged = false;            ///< a non-finite value appeared; the run stopped there
  /// Wall time of the simulation per frame: the median of `timed_runs` runs of the setting from
  /// its initial state, after the measured run above as a warm-up (at least 3 runs and about
  /// 0.5 s in all; the references and a diverged run: their one run)
  double ms_per_frame = 0.0;
  double ms_per_frame_min = 0.0;    ///< the fastest and slowest of those runs
  double ms_per_frame_max = 0.0;
  double ms_per_frame_q1 = 0.0;     ///< their quartiles: the spread (one preempted run moves only min/max)
  double ms_per_frame_q3 = 0.0;
  int timed_runs = 0;
  double error_rms = 0.0;           ///< against the reference, in spacings (0 for the reference)
  double error_max = 0.0;
  RunErrors constraint_errors;      ///< the run report's errors over the run (empty: not measured)
  bool pareto = false;              ///< on the Pareto front of time against rms error
};

struct BenchResult {
  std::string scene;
  std::vector<std::string> axes;  ///< swept keys
  std::string reference;          ///< the reference's method and settings, in words
  double spacing = 1.0;           ///< m, the length errors are measured in
  std::string spacing_source;     ///< what that length is ("fluid spacing", ...)
  int frames = 0;
  int threads = 0;
  std::size_t particles = 0;
  std::vector<BenchRun> runs;     ///< the sweep in order, then the reference, then its check

  const BenchRun& reference_run() const;
  const BenchRun& reference_check() const;
};

/// Loads the scene with these overrides (the bench's own, after the user's --set).
using SceneFactory = std::function<SceneDef(const std::vector<std::string>& overrides)>;

/// Checks the sweep without running anything: every swept scene loads, no key is swept twice,
/// the reference asked for can model the scene. Throws what run_bench would.
void check_bench(const SceneFactory& load_scene, const BenchOptions& options);

/// Runs the sweep and the references. Throws BenchError, SceneError (a swept value the scene
/// rejects) or std::runtime_error (the reference diverged: it cannot judge anything).
BenchResult run_bench(const SceneFactory& load_scene, const BenchOptions& options);

/// The result as CSV: a header line, then one row per run (sweep, reference, reference check).
std::string bench_csv(const BenchResult& result);

/// The result as a table for the terminal, with the reference's settings and its own error.
void print_bench_table(std::ostream& out, const BenchResult& result);

}  // namespace seiche
