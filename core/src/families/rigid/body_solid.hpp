// A rigid body's solid in its own frame (centre of mass at the origin, axes the body's), as one
// surface of world_surfaces.hpp, so that its penetration() query answers for the body: a box
// [-size/2, size/2], a sphere or a capsule about the origin (the capsule's segment along y), a
// mesh through the signed distance field of its body-frame surface (body_surface.hpp), sampled as
// the mesh colliders are (a voxel of 1/64 of the mesh's largest extent, a band of 4 voxels).
// The particles' contacts with bodies (particle_body_contacts.hpp) and the fluid's
// (families/fluid_body/) keep particles out of the bodies with it.
#pragma once

#include <cstddef>
#include <memory>

#include "body_shape.hpp"
#include "families/collider/mesh_sdf.hpp"
#include "seiche/scene.hpp"
#include "world_surfaces.hpp"

namespace seiche::rigid {

/// A mesh body's field (body `index` of the scene: "rigid_bodies[index].mesh" in its errors).
std::shared_ptr<const MeshSdf> body_mesh_sdf(const RigidBodyDef& def, std::size_t index);

/// The mesh bodies' fields, each built on its first request and shared after: the contacts
/// between bodies, the particles' contacts with bodies and the fluid boundary all read the same
/// field (once a field of 64 voxels along the body's longest edge was built by each). Requests
/// come while the families are built, serially.
class BodyMeshFields {
 public:
  explicit BodyMeshFields(const std::vector<RigidBodyDef>& defs) : defs_(&defs), fields_(defs.size()) {}
  /// Body k's field, or null when body k is not a mesh.
  std::shared_ptr<const MeshSdf> get(std::size_t k);

 private:
  const std::vector<RigidBodyDef>* defs_;
  std::vector<std::shared_ptr<const MeshSdf>> fields_;
};
/// The solid of shape `d`; a mesh's through `sdf` (owned by the caller).
SolidSurface body_solid(const ShapeDims& d, const MeshSdf* sdf);

}  // namespace seiche::rigid
