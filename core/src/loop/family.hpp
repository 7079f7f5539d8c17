// A constraint family: what the substep asks of every material (fluid, cloth, raw distance
// constraints, particle contacts, colliders, and the motion every particle has), and the stages
// a substep runs.
//
// A family declares its passes, each with the stage it belongs to and an order key within the
// stage; Simulation::substep() runs the stages in order and, in each, the passes of every family
// in the order of their keys. The keys of all families are in one table (pass_order below), so
// the whole substep reads in one place, and the run report's pipeline list is the same table.
// A pass works on the store's columns or on the packed iteration record (Layout,
// iteration_record.hpp); the loop packs or unpacks between passes, never a family.
// After the store is reordered, every family remaps the particle indices it holds; after the
// fixed iterations, families may vote for more (the fluid's density tolerance); at the end of a
// frame, each measures the error of its constraints; a checkpoint saves and restores the state it
// carries across substeps.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "iteration_record.hpp"
#include "seiche/checkpoint_chunks.hpp"
#include "seiche/frame_metrics.hpp"
#include "seiche/kernels/packed_positions.hpp"
#include "seiche/simulation.hpp"

namespace seiche {

/// The stages of a substep, in the order they run (docs/design.md, "One substep").
enum class Stage : int {
  Predict,       ///< v += dt g, p = x + dt v
  Neighbors,     ///< grids and neighbor lists on the predicted positions (may reorder the store)
  BeginSubstep,  ///< per-substep resets (XPBD multipliers)
  Iterate,       ///< the constraint passes, `iterations` times or more (see Family::wants_iteration)
  Update,        ///< v = (p - x) / dt, x = p
  Velocity,      ///< velocity passes: damping, vorticity, viscosity
};
inline constexpr int kStageCount = int(Stage::Velocity) + 1;

/// Where each pass runs within its stage, ascending: every family's keys in one table.
namespace pass_order {
inline constexpr int kPredict = 0;           // Predict
inline constexpr int kBodyPredict = 10;      //   rigid bodies: their own state, not particles
inline constexpr int kFluidNeighbors = 0;    // Neighbors: reorders the store, so it comes first
inline constexpr int kContactPairs = 10;     //   reads the fluid's grid of this substep
inline constexpr int kParticleBodyPairs = 20;  // on the bodies' predicted poses
inline constexpr int kFluidShapePairs = 30;  //   fluid-shape pairs of the density, in the fluid's grid
inline constexpr int kDistanceReset = 0;     // BeginSubstep
inline constexpr int kClothReset = 10;
inline constexpr int kJointReset = 20;
inline constexpr int kFluidBodyBoundary = -1;  // Iterate: the bodies' boundary particles' density
inline constexpr int kFluidDensity = 0;      //   reads it
inline constexpr int kFluidBodyDensity = 1;  //   the boundary's part of the correction, the bodies' reaction
inline constexpr int kDistanceForests = 9;   // on the columns, before the colored constraints
inline constexpr int kDistance = 10;
inline constexpr int kClothStretchForests = 19;  // on the columns, before the colored edges
inline constexpr int kClothStretch = 20;     //   distance, stretch and bending share one pack
inline constexpr int kClothBending = 21;
inline constexpr int kTethers = 22;
inline constexpr int kParticleContacts = 30;
inline constexpr int kShapeMatching = 40;    //   after the contacts: its clusters end rigid
inline constexpr int kParticleBodyContacts = 45;  // cloth and shapes against bodies, two-way
inline constexpr int kJoints = 50;           //   rigid bodies only (no particle is moved)
inline constexpr int kBodyContacts = 51;     //   after the joints: a body ends out of the world
inline constexpr int kFluidBodySeparation = 52;  // after the bodies moved: no fluid ends inside one
inline constexpr int kCollisions = 100;      //   last: nothing is pushed into a collider after it
inline constexpr int kUpdate = 0;            // Update
inline constexpr int kBodyUpdate = 10;
inline constexpr int kBodyContactVelocities = 11;  // friction and restitution on the new velocities
inline constexpr int kShapePlasticity = 20;   //   on the positions the substep ends with
inline constexpr int kDamping = 0;           // Velocity
inline constexpr int kVorticity = 10;
inline constexpr int kViscosity = 20;
inline constexpr int kFluidBodyViscosity = 21;  //   the bodies' and shapes' boundary in XSPH
}  // namespace pass_order

struct Pass {
  const char* name;  ///< as the pass timer and the run report's pipeline list name it
  Stage stage;
  int order;         ///< within the stage, ascending (pass_order)
  bool reported;     ///< timed and listed in the pipeline (a per-substep reset is neither)
  std::function<void(const StepContext&)> run;
  /// Where it reads and writes the predicted positions: Packed passes get the iteration record
  /// as StepContext::packed (current when they run), and may write only its positions.
  Layout layout = Layout::Columns;
};

class Family {
 public:
  virtual ~Family() = default;
  /// Appends the passes this family runs (only those its scene section needs).
  virtual void add_passes(std::vector<Pass>& passes) = 0;
  /// After the store was reordered: new_index[old] for every particle index the family holds.
  virtual void remap(std::span<const std::uint32_t> new_index) { (void)new_index; }
  /// The store indices its Layout::Packed passes gather (empty without such passes): the
  /// iteration record covers the union of the families' ranges. Asked again after a reorder.
  virtual kernels::IndexRange packed_range() const { return {}; }
  /// Whether this family may ask for iterations past solver.iterations (up to max_iterations).
  virtual bool votes_on_iterations() const { return false; }
  /// After an iteration, from the fixed count on: whether this family wants another.
  virtual bool wants_iteration() const { return false; }
  /// Its part of the frame's metrics: its constraints' error on the store's final positions.
  /// Only reads the store.
  virtual void measure(FrameMetrics& m) { (void)m; }
  /// The state it carries from one substep to the next beyond the store's State columns, for
  /// checkpoints: saved as named chunks ("<family>.<what>", checkpoint_chunks.hpp) and restored
  /// into a family built from the same scene, after the store (restore checks the sizes and
  /// throws ResumeError). Nothing by default.
  virtual void save_state(CheckpointChunks& chunks) const { (void)chunks; }
  virtual void restore_state(const CheckpointChunks& chunks) { (void)chunks; }
};

}  // namespace seiche
