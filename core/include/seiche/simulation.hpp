// The simulation: owns the particle store and the constraint families of a scene (fluid, cloth,
// raw distance constraints, particle contacts, colliders, and the motion every particle has;
// core/src/loop/family.hpp), and steps them.
//
// One substep (XPBD, "small steps") runs the stages in order, each stage the passes of every
// family in the order of their keys (pass_order in core/src/loop/family.hpp):
//   predict          v += dt g, p = x + dt v
//   neighbors        cell keys -> counting sort -> reorder the store -> neighbor lists;
//                    candidate particle pairs of cloth contacts
//   begin substep    XPBD multipliers reset
//   iterations x     every constraint pass (fluid density, distance, cloth, contacts, collisions);
//                    with a density tolerance, more while the fluid is too compressed
//   update           v = (p - x) / dt, x = p
//   velocity passes  damping, vorticity confinement, XSPH viscosity
// A family and its passes exist only if the scene needs them; the run report's pipeline list is
// the same table.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "seiche/checkpoint_chunks.hpp"
#include "seiche/frame_metrics.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/pass_timer.hpp"
#include "seiche/scene.hpp"

namespace seiche {

namespace kernels {
class PackedPositions;
}
class DistanceSolver;
class ClothSolver;
class Family;
class FluidFamily;
class DistanceFamily;
class ClothFamily;
class RigidFamily;
struct BodyPose;
class IterationRecord;
struct Pass;

/// Whether Simulation::step_frame measures the frame (FrameMetrics). Measuring never changes
/// the simulation: a run measured every frame and one never measured have the same bits
/// (tested); Skip only saves its time.
enum class FrameMeasure { Full, Skip };

/// What every pass sees during one substep.
struct StepContext {
  float dt = 0.0f;  ///< substep length (s)
  int substep = 0;
  int iteration = 0;
  /// The iteration record (core/src/loop/iteration_record.hpp), current during a pass that
  /// declares Layout::Packed; the loop packs and unpacks it, a pass never does.
  const kernels::PackedPositions* packed = nullptr;
};

class Simulation {
 public:
  explicit Simulation(const SceneDef& scene);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  /// Advances one frame (solver.substeps substeps) and returns its metrics. With
  /// FrameMeasure::Skip only frame, time, particles and the iteration counts are filled in (no
  /// health check: non_finite stays 0 whatever the state).
  FrameMetrics step_frame(FrameMeasure measure = FrameMeasure::Full);

  const SceneDef& scene() const { return scene_; }
  const ParticleStore& particles() const { return store_; }
  const PassTimer& timer() const { return timer_; }
  int frame() const { return frame_; }
  double time() const { return time_; }

  /// The cloths of the scene (meshes, vertex ids, constraint counts), or null when it has none.
  const ClothSolver* cloth() const;
  /// The raw distance constraints, or null when the scene has none.
  const DistanceSolver* distance() const;
  /// Every rigid body's position, orientation and velocities now, in scene order (empty
  /// without bodies).
  std::vector<BodyPose> body_poses() const;
  /// How many particles were created outside the domain and moved to its nearest point (only
  /// a scene built in code can do that: the scene loader rejects such files).
  std::size_t moved_into_domain() const { return moved_into_domain_; }

  /// The state's health now (energies, max speed, non-finite values, particles outside the
  /// domain), without the constraint errors: what step_frame's metrics start from, and how a
  /// caller measures the state before the first frame.
  FrameMetrics state_metrics() const;

  /// Names of the passes this scene's pipeline runs, in order.
  std::vector<std::string> pipeline() const;

  /// Continues from a saved state (a checkpoint, checkpoint.hpp): `saved` holds every State
  /// column of this store (by name) in the saved order, its ids a permutation of this store's
  /// ids; `frames_done` the frames it had stepped. Reorders this store into the saved order
  /// (remapping every index held elsewhere, as the neighbor stage does), then overwrites the
  /// State columns and the frame count; with restore_family_state, stepping on is bit-identical
  /// to never having stopped.
  void restore_state(const ParticleStore& saved, int frames_done);
  /// The state every family carries from one substep to the next (Family::save_state), as the
  /// checkpoint's named chunks, and its restoring (after restore_state; throws ResumeError when a
  /// chunk is missing or of the wrong size).
  CheckpointChunks family_state() const;
  void restore_family_state(const CheckpointChunks& chunks);

 private:
  void create_families();
  void move_into_domain();
  void assemble_pipeline();

  /// One substep: the stages in order, each running its passes (pass_order in family.hpp); the
  /// Iterate stage `iterations` times, then more while a family votes for it (up to the cap).
  void substep(StepContext& ctx);
  void run_stage(int stage, const StepContext& ctx);
  bool a_family_wants_iteration() const;
  /// Reorders the store (new k = old order[k]) and remaps every index held elsewhere.
  void reorder(std::span<const std::uint32_t> order);
  /// The iteration record's range: the union of the families' packed ranges.
  void reset_record_range();
  /// The frame's constraint errors on top of state_metrics(). Reads the state and writes only
  /// measuring scratch, so that it cannot change what the next substep computes.
  FrameMetrics measure();

  SceneDef scene_;
  ParticleStore store_;
  PassTimer timer_;

  // The families of this scene, in the order they were built (family.hpp); the typed pointers
  // name the ones other code asks for (null when the scene has none).
  std::vector<std::unique_ptr<Family>> families_;
  FluidFamily* fluid_ = nullptr;
  DistanceFamily* distance_ = nullptr;
  ClothFamily* cloth_ = nullptr;
  RigidFamily* rigid_ = nullptr;
  // Every family's passes, sorted by (stage, order); stage s runs passes_[stage_begin_[s],
  // stage_begin_[s + 1]).
  std::vector<Pass> passes_;
  std::vector<std::size_t> stage_begin_;
  // The predicted positions packed for the passes that gather (the store's px, py, pz own them);
  // run_stage packs and unpacks it between passes by their Layout.
  std::unique_ptr<IterationRecord> record_;
  int iteration_cap_ = 1;  // max(iterations, max_iterations) when a family votes, else iterations
  std::size_t moved_into_domain_ = 0;
  int frame_ = 0;
  double time_ = 0.0;
};

}  // namespace seiche
