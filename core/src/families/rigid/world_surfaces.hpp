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
// walls, the collider's own).
// The same solids serve the contacts between bodies (body_contacts.hpp): a body's own shape as a
// box, sphere, capsule or mesh field in its body frame (body_solid), queried with the point moved
// into that frame.
#pragma once

#include <memory>
#include <vector>

#include "families/collider/mesh_sdf.hpp"
#include "rigid_math.hpp"
#include "seiche/scene.hpp"

namespace seiche::rigid {

struct SurfacePenetration {
  double depth = 0.0;  ///< > 0: in contact (m)
  Vec3d normal;        ///< unit, out of the surface
};

/// One solid: a plane (point a, unit normal b), a box [a, b], a sphere (centre a, radius), a
/// capsule (ends a and b, radius) or a closed mesh's signed distance field.
struct Solid {
  ColliderDef::Shape shape = ColliderDef::Shape::Plane;  // the domain's walls are planes
  Vec3d a, b;
  double radius = 0.0;    // sphere, capsule
  double friction = 0.0;  // a world surface's Coulomb coefficient
  const MeshSdf* sdf = nullptr;
};

/// How deep the ball (p, r) reaches into `solid` (formulas above); false where it does not.
bool solid_penetration(const Solid& solid, Vec3d p, double r, SurfacePenetration& out);

/// The shape of body `index` (`def`) as a solid in its body frame: a box centred at the origin, a sphere at the
/// origin, a capsule along y, or a mesh body's field (`keep` receives the field, which the solid
/// points to: samples of a 32nd of the mesh's largest side, over its box grown by 4 samples).
Solid body_solid(const RigidBodyDef& def, std::size_t index, std::shared_ptr<const MeshSdf>& keep);

class WorldSurfaces {
 public:
  WorldSurfaces() = default;
  explicit WorldSurfaces(const SceneDef& scene);

  int count() const { return int(surfaces_.size()); }
  double friction(int surface) const { return surfaces_[std::size_t(surface)].friction; }
  /// How deep the ball (p, r) reaches into `surface`; false where it does not (depth <= 0).
  bool penetration(int surface, Vec3d p, double r, SurfacePenetration& out) const {
    return solid_penetration(surfaces_[std::size_t(surface)], p, r, out);
  }

 private:
  std::vector<Solid> surfaces_;
  std::vector<std::shared_ptr<const MeshSdf>> mesh_sdfs_;  // the mesh colliders' fields
};

}  // namespace seiche::rigid
