// A rigid body's solid in its own frame (the shapes are in body_solid.hpp).
#include "body_solid.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "body_surface.hpp"
#include "families/cloth/cloth_mesh.hpp"

namespace seiche::rigid {

std::shared_ptr<const MeshSdf> body_mesh_sdf(const RigidBodyDef& def, std::size_t index) {
  const BodySurface surface = body_surface(def);
  ClothMesh mesh;
  for (const Vec3d& v : surface.vertices)
    mesh.positions.push_back({float(v.x), float(v.y), float(v.z)});
  mesh.triangles = surface.triangles;
  float extent = 0.0f;
  for (int a = 0; a < 3; ++a) {
    float lo = INFINITY, hi = -INFINITY;
    for (const Vec3& x : mesh.positions) lo = std::min(lo, x[a]), hi = std::max(hi, x[a]);
    extent = std::max(extent, hi - lo);
  }
  const float voxel = std::max(extent / 64.0f, 1e-6f);
  auto sdf = std::make_shared<MeshSdf>();
  build_mesh_sdf(mesh, voxel, 4.0f * voxel, def.mesh.file,
                 "rigid_bodies[" + std::to_string(index) + "].mesh", *sdf);
  return sdf;
}

std::shared_ptr<const MeshSdf> BodyMeshFields::get(std::size_t k) {
  const RigidBodyDef& def = (*defs_)[k];
  if (body_shape_def(def).shape != BodyShape::Mesh) return nullptr;
  if (!fields_[k]) fields_[k] = body_mesh_sdf(def, k);
  return fields_[k];
}

SolidSurface body_solid(const ShapeDims& d, const MeshSdf* sdf) {
  SolidSurface s;
  switch (d.shape) {
    case BodyShape::Box:
      s.shape = ColliderDef::Shape::Box, s.a = -0.5 * d.size, s.b = 0.5 * d.size;
      break;
    case BodyShape::Sphere:
      s.shape = ColliderDef::Shape::Sphere, s.radius = d.radius;
      break;
    case BodyShape::Capsule:
      s.shape = ColliderDef::Shape::Capsule, s.radius = d.radius;
      s.a = {0.0, -0.5 * d.length, 0.0}, s.b = {0.0, 0.5 * d.length, 0.0};
      break;
    case BodyShape::Mesh:
      s.shape = ColliderDef::Shape::Mesh, s.sdf = sdf;
      break;
  }
  return s;
}

}  // namespace seiche::rigid
