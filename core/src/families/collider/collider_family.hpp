// The colliders: the domain's box, always, and the scene's shapes and meshes (a mesh through its
// signed distance field, mesh_sdf.hpp). One pass, the last of every iteration: every particle is
// pushed out of every collider by its collision radius, with friction (kernels/collisions.hpp).
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "loop/family.hpp"
#include "mesh_sdf.hpp"
#include "seiche/kernels/collisions.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class ColliderFamily final : public Family {
 public:
  /// `fluid_radius`: the fluid particles' collision radius (0 without fluid); `cloth_radius`:
  /// the cloth particles' radii by cloth (empty without cloth; the family keeps the pointer).
  ColliderFamily(const SceneDef& scene, ParticleStore& store, float fluid_radius,
                 std::span<const float> cloth_radius);

  void add_passes(std::vector<Pass>& passes) override;

 private:
  ParticleStore& store_;
  std::vector<std::unique_ptr<MeshSdf>> mesh_sdfs_;  // the fields of the mesh colliders
  kernels::CollisionParams params_;
  std::vector<kernels::CollisionShape> shapes_;
};

}  // namespace seiche
