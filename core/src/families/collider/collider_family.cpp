#include "collider_family.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "families/cloth/cloth_mesh.hpp"

namespace seiche {

// Mesh colliders: the field's samples are a 64th of the mesh's largest side unless the scene
// says otherwise, over the mesh's box grown by 4 samples.
std::unique_ptr<MeshSdf> build_collider_sdf(const ColliderDef& c, std::size_t index) {
  const std::string path = "colliders[" + std::to_string(index) + "].mesh";
  // The OBJ as the scene loader read it; a definition made in code has none: read the file.
  const ClothMesh read_here = c.loaded_mesh ? ClothMesh{} : read_obj_mesh(c.mesh.file, c.mesh, path);
  const ClothMesh& mesh = c.loaded_mesh ? *c.loaded_mesh : read_here;
  float voxel = c.voxel_size;
  if (voxel <= 0.0f) {
    float extent = 0.0f;
    for (int a = 0; a < 3; ++a) {
      float lo = INFINITY, hi = -INFINITY;
      for (const Vec3& x : mesh.positions) lo = std::min(lo, x[a]), hi = std::max(hi, x[a]);
      extent = std::max(extent, hi - lo);
    }
    voxel = std::max(extent / 64.0f, 1e-6f);
  }
  auto sdf = std::make_unique<MeshSdf>();
  build_mesh_sdf(mesh, voxel, 4.0f * voxel, c.mesh.file, path, *sdf);
  return sdf;
}

namespace {

kernels::CollisionShape to_shape(const ColliderDef& c, const MeshSdf* sdf) {
  kernels::CollisionShape s;
  s.friction = c.friction;
  switch (c.shape) {
    case ColliderDef::Shape::Plane:
      s.kind = kernels::CollisionShape::Kind::Plane;
      std::copy(c.point.begin(), c.point.end(), s.a);
      std::copy(c.normal.begin(), c.normal.end(), s.b);
      break;
    case ColliderDef::Shape::Box:
      s.kind = kernels::CollisionShape::Kind::Box;
      std::copy(c.box.min.begin(), c.box.min.end(), s.a);
      std::copy(c.box.max.begin(), c.box.max.end(), s.b);
      break;
    case ColliderDef::Shape::Sphere:
      s.kind = kernels::CollisionShape::Kind::Sphere;
      std::copy(c.center.begin(), c.center.end(), s.a);
      s.radius = c.radius;
      break;
    case ColliderDef::Shape::Capsule:
      s.kind = kernels::CollisionShape::Kind::Capsule;
      std::copy(c.end_a.begin(), c.end_a.end(), s.a);
      std::copy(c.end_b.begin(), c.end_b.end(), s.b);
      s.radius = c.radius;
      break;
    case ColliderDef::Shape::Mesh:
      s.kind = kernels::CollisionShape::Kind::Sdf;
      s.sdf = &sdf->grid;
      break;
  }
  return s;
}

}  // namespace

ColliderFamily::ColliderFamily(const SceneDef& scene, ParticleStore& store) : store_(store) {
  for (int a = 0; a < 3; ++a) {
    params_.domain_min[a] = scene.domain.min[a];
    params_.domain_max[a] = scene.domain.max[a];
  }
  params_.domain_friction = scene.domain.friction;
  for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
    const ColliderDef& c = scene.colliders[k];
    if (c.shape == ColliderDef::Shape::Mesh) mesh_sdfs_.push_back(build_collider_sdf(c, k));
    shapes_.push_back(to_shape(c, c.shape == ColliderDef::Shape::Mesh ? mesh_sdfs_.back().get() : nullptr));
  }
}

void ColliderFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"collisions", Stage::Iterate, pass_order::kCollisions, true, [this](const StepContext&) {
                      kernels::solve_collisions(particle_view(store_), params_, shapes_);
                    }});
}

}  // namespace seiche
