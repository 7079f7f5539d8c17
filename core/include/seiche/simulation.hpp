// The simulation: owns the particle store and the constraint data of a scene, assembles the
// substep pipeline from what the scene contains, and steps it.
//
// One substep (XPBD, "small steps"):
//   predict          v += dt g, p = x + dt v
//   neighbors        cell keys -> counting sort -> reorder the store -> neighbor lists
//   contact pairs    candidate particle pairs of cloth contacts (particle_contact_stage.hpp)
//   iterations x     every constraint pass (fluid density, distance, collisions, ...); with a
//                    density tolerance, more while the fluid is too compressed
//   update           v = (p - x) / dt, x = p
//   velocity passes  vorticity confinement, XSPH viscosity
// A pass exists only if the scene needs it; new materials add their passes to the lists.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "seiche/frame_metrics.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/pass_timer.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class FluidSolver;
class DistanceSolver;
class ClothSolver;
class ParticleContactStage;
class FluidErrorProbe;
struct MeshSdf;
struct Neighborhood;
namespace kernels {
struct ParticleView;
struct CollisionShape;
struct CollisionParams;
}  // namespace kernels

/// Whether Simulation::step_frame measures the frame (FrameMetrics). Measuring never changes
/// the simulation: a run measured every frame and one never measured have the same bits
/// (tested); Skip only saves its time.
enum class FrameMeasure { Full, Skip };

/// What every pass sees during one substep.
struct StepContext {
  float dt = 0.0f;  ///< substep length (s)
  int substep = 0;
  int iteration = 0;
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
  const ClothSolver* cloth() const { return cloth_.get(); }
  /// The raw distance constraints, or null when the scene has none.
  const DistanceSolver* distance() const { return distance_.get(); }
  /// How many particles were created outside the domain and moved to its nearest point (only
  /// a scene built in code can do that: the scene loader rejects such files).
  std::size_t moved_into_domain() const { return moved_into_domain_; }

  /// The state's health now (energies, max speed, non-finite values, particles outside the
  /// domain), without the constraint errors: what step_frame's metrics start from, and how a
  /// caller measures the state before the first frame.
  FrameMetrics state_metrics() const;

  /// Names of the passes this scene's pipeline runs, in order.
  std::vector<std::string> pipeline() const;

  /// Continues from a saved state (a checkpoint, checkpoint.hpp): `saved` holds every state
  /// column in the saved order, its ids a permutation of this store's ids; `frames_done` the
  /// frames it had stepped. Reorders this store into the saved order (remapping every index held
  /// elsewhere, as the neighbor stage does), then overwrites the state columns and the frame
  /// count, so that stepping on is bit-identical to never having stopped.
  void restore_state(const ParticleStore& saved, int frames_done);
  /// The cloth stretch multipliers of the last substep, which the stretch forests read in the
  /// next one (empty without forests), and their restoring from a checkpoint (same size).
  std::span<const float> cloth_stretch_multipliers() const;
  void restore_cloth_stretch_multipliers(std::span<const float> saved);

 private:
  struct Pass {
    const char* name;
    std::function<void(const StepContext&)> run;
  };

  void create_particles();
  void move_into_domain();
  void create_distance_constraints();
  void create_colliders();
  void assemble_pipeline();

  void substep(StepContext& ctx);
  /// After the fixed iterations: whether the fluid's mean density error at the start of the last
  /// iteration exceeds solver.density_tolerance (false without fluid or tolerance).
  bool fluid_needs_iteration() const;
  void find_neighbors();
  /// Reorders the store (new k = old order[k]) and remaps every index held elsewhere.
  void reorder(std::span<const std::uint32_t> order);
  /// The frame's constraint errors on top of state_metrics(). Reads the state and writes only
  /// measuring scratch (fluid_probe_), so that it cannot change what the next substep computes.
  FrameMetrics measure();

  SceneDef scene_;
  ParticleStore store_;
  PassTimer timer_;
  kernels::ParticleView view();

  std::unique_ptr<Neighborhood> neighborhood_;  // null when no pass needs neighbors
  std::unique_ptr<FluidSolver> fluid_;
  std::unique_ptr<FluidErrorProbe> fluid_probe_;  // with fluid_: the frame's density error
  std::unique_ptr<DistanceSolver> distance_;
  std::unique_ptr<ClothSolver> cloth_;
  std::unique_ptr<ParticleContactStage> contacts_;    // null unless particles of cloth can touch
  std::vector<std::unique_ptr<MeshSdf>> mesh_sdfs_;   // the fields of the mesh colliders
  std::unique_ptr<kernels::CollisionParams> collision_params_;
  std::vector<kernels::CollisionShape> colliders_;
  float density_tolerance_ = 0.0f;  // 0 without fluid: the fixed iteration count
  int iteration_cap_ = 1;           // max(iterations, max_iterations) with a tolerance, else iterations
  std::vector<Pass> begin_substep_passes_;  // reset per-substep state (XPBD lambdas)
  std::vector<Pass> constraint_passes_;     // run every iteration, in order
  std::vector<Pass> velocity_passes_;       // run after the velocity update
  std::vector<std::function<void(std::span<const std::uint32_t>)>> index_remappers_;
  std::size_t moved_into_domain_ = 0;
  int frame_ = 0;
  double time_ = 0.0;
};

}  // namespace seiche
