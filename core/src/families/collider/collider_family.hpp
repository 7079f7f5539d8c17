// The colliders: the domain's box, always, and the scene's shapes and meshes (a mesh through its
// signed distance field, mesh_sdf.hpp). One pass, the last of every iteration: every particle is
// pushed out of every collider by its collision radius, with friction (kernels/collisions.hpp).
#pragma once

#include <memory>
#include <vector>

#include "loop/family.hpp"
#include "mesh_sdf.hpp"
#include "seiche/kernels/collisions.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// The signed distance field of mesh collider `c` (scene.colliders[index]): sampled at its
/// `voxel_size`, or a 64th of the mesh's largest side, over the mesh's box grown by 4 samples. The
/// collider family builds it once; the particles' collisions and the rigid bodies' contacts
/// (families/rigid/world_surfaces.hpp) share it.
std::unique_ptr<MeshSdf> build_collider_sdf(const ColliderDef& c, std::size_t index);

class ColliderFamily final : public Family {
 public:
  /// Every particle keeps its store radius (the radius column, written by its family) from
  /// the colliders' surfaces.
  ColliderFamily(const SceneDef& scene, ParticleStore& store);

  void add_passes(std::vector<Pass>& passes) override;

  /// The fields of the mesh colliders, one per mesh collider in scene order: the rigid bodies'
  /// contacts share them (a field is built once per scene).
  const std::vector<std::shared_ptr<const MeshSdf>>& mesh_fields() const { return mesh_sdfs_; }

 private:
  ParticleStore& store_;
  std::vector<std::shared_ptr<const MeshSdf>> mesh_sdfs_;  // the fields of the mesh colliders
  kernels::CollisionParams params_;
  std::vector<kernels::CollisionShape> shapes_;
};

}  // namespace seiche
