// The cloths of a scene (cloth_solver.hpp): their vertices in the store, the XPBD multipliers
// reset every substep, stretch, bending and tethers every iteration (the colored stretch and
// bending on the iteration record), the constraints' particle indices remapped after a reorder,
// strain and bending error measured at the end of a frame, the stretch multipliers carried
// across substeps saved in checkpoints.
#pragma once

#include <memory>

#include "cloth_solver.hpp"
#include "loop/family.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class ClothFamily final : public Family {
 public:
  /// Reads the cloths' meshes; their vertices are written by create().
  ClothFamily(const SceneDef& scene, ParticleStore& store)
      : store_(store), solver_(std::make_unique<ClothSolver>(scene)) {}

  std::size_t particle_count() const { return solver_->vertex_count(); }
  /// Writes the vertices at store indices [first, first + particle_count()) and builds the
  /// constraints on those rest positions.
  void create(std::size_t first) { solver_->create(store_, first, particle_view(store_)); }

  const ClothSolver& solver() const { return *solver_; }
  ClothSolver& solver() { return *solver_; }

  void add_passes(std::vector<Pass>& passes) override;
  void remap(std::span<const std::uint32_t> new_index) override { solver_->remap(new_index); }
  kernels::IndexRange packed_range() const override { return solver_->packed_range(); }
  void measure(FrameMetrics& m) override;
  /// The stretch forests' multipliers of the last substep, which their geometric stiffness reads
  /// in the next one (kernels/distance_tree.hpp): chunk "cloth.stretch_multipliers", in the
  /// constraints' (scene-determined) order, empty without forests.
  void save_state(CheckpointChunks& chunks) const override;
  void restore_state(const CheckpointChunks& chunks) override;

 private:
  ParticleStore& store_;
  std::unique_ptr<ClothSolver> solver_;
};

}  // namespace seiche
