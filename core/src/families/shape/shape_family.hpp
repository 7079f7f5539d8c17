// Rigid and soft particle clusters kept in shape by shape matching (kernels/shape_matching.hpp;
// Müller et al. 2005). Scene section "shapes": each entry a box filled with particles on a
// lattice, one cluster; stiffness 1 is rigid, less is soft (a linear pull toward the rigid goal
// every iteration).
//
// What the family holds and where:
//   store columns   shape.rest_x/y/z (Constant): each particle's rest offset from its cluster's
//                   rest centre of mass; the store moves them with the particles on a reorder
//   clusters        member lists (store indices, remapped after a reorder) and stiffness
//   state           every cluster's rotation of the last solve: the warm start of the next one,
//                   carried across substeps and saved in checkpoints as chunk "shape.rotations"
// Pass: "shape matching" every iteration (pass_order::kShapeMatching), before the collisions.
// Error row "shape_error": each particle's distance from its cluster's rigid fit on the final
// positions, in units of the cluster's spacing.
#pragma once

#include <cstddef>
#include <vector>

#include "loop/family.hpp"
#include "seiche/kernels/shape_matching.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class ShapeFamily final : public Family {
 public:
  /// Particles of all the scene's shapes.
  static std::size_t particle_count(const SceneDef& scene);

  /// Writes the shapes' particles at store indices [first, first + particle_count(scene)) and
  /// adds the family's columns to the store.
  ShapeFamily(const SceneDef& scene, ParticleStore& store, std::size_t first);

  void add_passes(std::vector<Pass>& passes) override;
  void remap(std::span<const std::uint32_t> new_index) override { clusters_.remap(new_index); }
  void measure(FrameMetrics& m) override;
  void save_state(CheckpointChunks& chunks) const override;
  void restore_state(const CheckpointChunks& chunks) override;

 private:
  kernels::RestOffsets rest() const { return {rest_x_.data(), rest_y_.data(), rest_z_.data()}; }

  ParticleStore& store_;
  FloatColumn &rest_x_, &rest_y_, &rest_z_;
  kernels::ShapeClusters clusters_;
  std::vector<float> spacing_;  // per cluster: the unit of its error row
};

}  // namespace seiche
