// The raw distance constraints of a scene ("distance_constraints", distance_solver.hpp): the
// XPBD multipliers reset every substep, every iteration the forests' exact solve (on the
// columns) and one colored solve (on the iteration record), the particle indices remapped after
// a reorder, |C| / rest_length measured at the end of a frame, the multipliers the forests carry
// across substeps saved in checkpoints.
#pragma once

#include <memory>

#include "distance_solver.hpp"
#include "loop/family.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class DistanceFamily final : public Family {
 public:
  /// The scene's constraints over the store's particles as they are now (rest_length < 0: the
  /// current distance).
  DistanceFamily(const SceneDef& scene, ParticleStore& store);

  const DistanceSolver& solver() const { return *solver_; }

  void add_passes(std::vector<Pass>& passes) override;
  void remap(std::span<const std::uint32_t> new_index) override { solver_->remap(new_index); }
  kernels::IndexRange packed_range() const override { return solver_->packed_range(); }
  void measure(FrameMetrics& m) override;
  /// The multipliers of the last substep, which the forests' geometric stiffness reads in the
  /// next one (kernels/distance_tree.hpp): chunk "distance.multipliers", in the constraints'
  /// (scene-determined) order, empty without forests.
  void save_state(CheckpointChunks& chunks) const override;
  void restore_state(const CheckpointChunks& chunks) override;

 private:
  ParticleStore& store_;
  std::unique_ptr<DistanceSolver> solver_;
};

}  // namespace seiche
