// Rigid, soft, linear and plastic particle bodies kept in shape by shape matching
// (kernels/shape_matching.hpp, shape_plasticity.hpp; Müller et al. 2005). Scene section "shapes":
// each entry a body of particles on a lattice (a box, a sphere, a voxelized closed OBJ mesh,
// shape_sites.hpp), one cluster, or overlapping region clusters (cluster_half_width k: cubes of
// half-width k cells centred at every k-th cell, so a particle is in 8 to 27 of them).
//
// What the family holds and where:
//   clusters        member lists (store indices, remapped after a reorder), each member's rest
//                   offset from its cluster's rest centre of mass (rebuilt from the scene on a
//                   resume), the clusters' settings, and the lists of shared particles
//   state           every cluster's rotation of the last solve (the warm start of the next one)
//                   and, for plastic bodies, its plastic deformation Sp of the rest shape: both
//                   carried across substeps and saved in checkpoints as chunks "shape.rotations"
//                   and "shape.plastic" (the latter only where a body is plastic)
// Passes: "shape matching" every iteration (pass_order::kShapeMatching), before the collisions;
// "shape plasticity" once per substep after the update (pass_order::kShapePlasticity), where a
// body is plastic.
// Error row "shape_error": per cluster, the RMS distance of its members from its best rigid fit
// (of its rest shape, plastic deformation included) on the final positions, relative to the
// cluster's size: the RMS distance of its members' rest positions from their rest centre of mass
// when the cluster was built (a plastic cluster's size stays that of the scene's shape),
//   e_c = sqrt(sum_k |x_k - g_k|^2 / n_c) / sqrt(sum_k |q_k|^2 / n_c)
// (g_k the fit's goal, q_k the rest offset, n_c the members); mean and max over the clusters.
#pragma once

#include <cstddef>
#include <vector>

#include "loop/family.hpp"
#include "seiche/kernels/shape_matching.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

struct ShapeSites;

class ShapeFamily final : public Family {
 public:
  /// Particles of all the scene's shapes.
  static std::size_t particle_count(const SceneDef& scene);

  /// Writes the shapes' particles at store indices [first, first + particle_count(scene)).
  ShapeFamily(const SceneDef& scene, ParticleStore& store, std::size_t first);

  void add_passes(std::vector<Pass>& passes) override;
  /// The id of the first shape particle (the shapes' particles have consecutive ids).
  std::int32_t first_id() const { return first_id_; }
  void remap(std::span<const std::uint32_t> new_index) override { clusters_.remap(new_index); }
  void measure(FrameMetrics& m) override;
  void save_state(CheckpointChunks& chunks) const override;
  void restore_state(const CheckpointChunks& chunks) override;

 private:
  void add_one_cluster(const ShapeDef& s, std::size_t begin, std::size_t end);
  void add_region_clusters(const ShapeDef& s, const ShapeSites& sites, std::size_t begin);

  ParticleStore& store_;
  kernels::ShapeClusters clusters_;
  std::vector<double> size_;    // per cluster: the RMS distance of its rest offsets, the error row's unit
  bool plastic_ = false;        // a body flows: the plasticity pass and chunk
  std::int32_t first_id_ = 0;
};

}  // namespace seiche
