// Particle-shape collisions as position constraints (Macklin et al. 2014, "Unified particle
// physics", sec. 6): a particle of radius r penetrating a shape by depth d along the shape's
// outward normal n is projected out,  p += d n.  Friction then removes the tangential part of
// the substep's displacement dx_t = (p - x) - ((p - x).n) n:
//   |dx_t| <= mu d:  p -= dx_t                          (static: sticks)
//   otherwise:       p -= dx_t * mu d / |dx_t|          (kinetic: slides, slowed)
// Shapes: the domain box (particles stay inside), half-spaces (plane), solid boxes, spheres,
// capsules (segment a-b grown by a radius) and signed distance fields (triangle meshes).
// A particle's radius is its entry in the radius column (ParticleView::radius): the families
// write it at creation (a fluid's particle radius, half a cloth's thickness, 0 for raw particles).
// Pinned particles (w = 0) are not moved.
#pragma once

#include <cstddef>
#include <span>

#include "seiche/kernels/particle_view.hpp"
#include "seiche/kernels/sdf_grid.hpp"

namespace seiche::kernels {

struct CollisionShape {
  enum class Kind { Plane, Box, Sphere, Capsule, Sdf };
  Kind kind = Kind::Plane;
  float a[3] = {0, 0, 0};  ///< plane: point; box: min; sphere: center; capsule: one end
  float b[3] = {0, 1, 0};  ///< plane: unit normal; box: max; capsule: the other end
  float radius = 0.0f;     ///< sphere, capsule
  float friction = 0.0f;
  const SdfGrid* sdf = nullptr;  ///< sdf: the field (owned by the caller)
};

struct CollisionParams {
  float domain_min[3] = {0, 0, 0};
  float domain_max[3] = {1, 1, 1};
  float domain_friction = 0.0f;
};

void solve_collisions(const ParticleView& p, const CollisionParams& params,
                      std::span<const CollisionShape> shapes);

}  // namespace seiche::kernels
