// The static world a rigid body touches: the domain's six walls (from inside) and the scene's
// colliders (plane, box, sphere, capsule, mesh through its signed distance field), as the
// collider family defines them for particles (kernels/collisions.hpp), in double precision
// except the mesh field (float32 samples). Each surface answers one question: how deep a ball of
// radius r centred at p reaches into it, and along which outward normal n it leaves:
//   domain wall a, lower:  d = (lo_a + r) - p_a,  n = +e_a    (upper: d = p_a - (hi_a - r), n = -e_a)
//   plane (point o, unit normal m):  d = r - (p - o).m,  n = m
//   sphere (centre c, radius R):     d = R + r - |p - c|,  n = (p - c) / |p - c|  (+y at the centre)
//   capsule: the sphere around the closest point of its segment
//   box [lo, hi]: inside the box grown by r, leave through the nearest face (d its distance)
//   mesh:  d = r - sdf(p), n = grad sdf; outside the field's box, from its nearest point c:
//          d = r - (sdf(c) + |p - c|), n = grad sdf(c)  (an upper bound of sdf(p), equal above a face)
// A contact is d > 0. Each surface has its Coulomb friction (the domain's `friction` for the
// walls, the collider's own). The same shapes, given in a rigid body's own frame, are the bodies'
// solids for the particles' contacts with them (particle_body_contacts.hpp): one query,
// penetration(), for both.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "families/collider/mesh_sdf.hpp"
#include "rigid_math.hpp"
#include "seiche/scene.hpp"

namespace seiche::rigid {

struct SurfacePenetration {
  double depth = 0.0;  ///< > 0: in contact (m)
  Vec3d normal;        ///< unit, out of the surface
};

/// One solid: a plane, box, sphere, capsule or mesh (its signed distance field), in whatever
/// frame the ball's centre is given in.
struct SolidSurface {
  ColliderDef::Shape shape = ColliderDef::Shape::Plane;  ///< the domain's walls are planes
  Vec3d a, b;            ///< plane: point, unit normal; box: min, max; sphere: centre; capsule: ends
  double radius = 0.0;   ///< sphere, capsule
  double friction = 0.0;
  const MeshSdf* sdf = nullptr;  ///< mesh: its field (owned by the caller)
};

/// How deep the ball (p, r) reaches into `s` (the formulas above); false where it does not
/// (depth <= 0).
bool penetration(const SolidSurface& s, Vec3d p, double r, SurfacePenetration& out);

class WorldSurfaces {
 public:
  WorldSurfaces() = default;
  /// The domain's walls and the scene's colliders; `mesh_fields` holds the fields of its mesh
  /// colliders, one per mesh collider in scene order (ColliderFamily::mesh_fields(): built once,
  /// shared); std::invalid_argument when one is null or their count is not the mesh colliders'.
  WorldSurfaces(const SceneDef& scene, std::span<const std::shared_ptr<const MeshSdf>> mesh_fields);

  int count() const { return int(surfaces_.size()); }
  double friction(int surface) const { return surfaces_[std::size_t(surface)].friction; }
  /// The surface itself (world frame; the domain's walls are planes).
  const SolidSurface& solid(int surface) const { return surfaces_[std::size_t(surface)]; }
  /// How deep the ball (p, r) reaches into `surface`; false where it does not (depth <= 0).
  bool penetration(int surface, Vec3d p, double r, SurfacePenetration& out) const {
    return rigid::penetration(surfaces_[std::size_t(surface)], p, r, out);
  }

 private:
  using Surface = SolidSurface;
  std::vector<Surface> surfaces_;
  std::vector<std::shared_ptr<const MeshSdf>> mesh_sdfs_;  // the mesh colliders' fields
};

}  // namespace seiche::rigid
