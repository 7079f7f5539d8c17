// Two-way coupling of the rigid bodies and the shape-matched particle bodies with the fluid
// (docs/design.md, "Fluid and rigid bodies", "Fluid and shapes"): each body's boundary particles
// (body_boundary.hpp) and every shape particle (shape_boundary.hpp) take part in the fluid's
// density constraint, and a separation keeps every fluid particle out of every body's solid; what
// either does to a fluid particle it does, reversed, to the body or the shape particle. (Fluid
// and shape particles are kept apart by the particle contact stage, particle_contact_stage.hpp.)
//
// Where the boundary particles live: in this family, in each body's frame, not in the particle
// store. They move only with their body, so their body-frame positions, volumes and grid are
// built once; a fluid particle near a body is turned into the body's frame and looks up the 27
// cells around it there. The store, the fluid's grid, its neighbor lists and its density kernels
// stay as they are: a scene without bodies runs the fluid exactly as before, and a scene without
// fluid builds no boundary.
//
// Per iteration, with x_b a site in the world and m the fluid particle's mass:
//   "fluid-body boundary" (before the fluid's density pass), for each fluid particle i near a
//     body: the boundary's density and its part of the constraint's gradient,
//       rho_b,i = sum_b rho0 psi_b W(|p_i - x_b|),   g_b,i = sum_b psi_b grad W(p_i - x_b)
//     which the fluid's pass adds to rho_i and to grad_{p_i} C_i (kernels/pbf_density.hpp), so
//     lambda_i sees the bodies as fluid; p_i is kept.
//   "fluid-body density" (after it), with the fluid's lambda_i of this iteration:
//       dp_i = lambda_i g_b,i   (the boundary's part of lambda_i grad_{p_i} C_i)
//     and each site's share, -m lambda_i psi_b grad W(p_i - x_b) at the kept p_i, is an impulse
//     on its body at x_b: the pair's momentum is kept exactly.
//   "fluid-body viscosity" (velocity stage, after the fluid's XSPH, where the fluid has a
//     viscosity c): the boundary particles in XSPH, with the boundary's velocity at each site
//     (a body's v + omega x (x_b - x_body); a shape particle's own velocity):
//       v_i += c sum_b psi_b (v_b - v_i) W(|x_i - x_b|)
//     so fluid at a body's wall is pulled toward the wall's velocity (no-slip, as XSPH pulls it
//     toward its fluid neighbours'). It reads v_i as the fluid's XSPH left it (split, not one
//     Jacobi sum). A shape particle gets the pair's reaction, from the velocities before the
//     pass, dv_b = -w_b m c sum_i psi_b W (v_b - v_i) (each pair keeps its momentum); a body gets
//     none (its drag comes from the density constraint and the separation). Vorticity
//     confinement does not see the boundary.
//   "fluid-body separation" (after the joints and the body contacts): a fluid particle whose
//     ball (radius s/2) reaches depth d into a body's solid along normal n (the solid's shape
//     query of body_solid.hpp in the body frame) is a contact:
//       dlambda = d / (1/m + w_body),  w_body = 1/M + (r x n)^T I^-1 (r x n),  r = p_i - x_body
//       p_i += dlambda / m n,  the body gets the impulse -dlambda n at r
// The run report's density error is of the same rho_i as the constraint's, boundary included: at
// the end of a frame, the fluid's error probe asks this family for rho_b,i + rho_s,i at the final
// positions (the bodies' sites at their poses then; the shape particles within h of each fluid
// particle in the probe's grid, summed shape particle by shape particle in the probe's order).
// Fluid particles write only their own positions (in parallel); the impulses on a body add up
// per block of particles and the blocks in index order, then move the body once (linear part
// through 1/M, angular through I^-1: body_correction.hpp), so the bits do not depend on the
// thread count.
#pragma once

#include <memory>
#include <vector>

#include "body_boundary.hpp"
#include "body_grid.hpp"
#include "shape_boundary.hpp"
#include "families/fluid/fluid_family.hpp"
#include "families/rigid/rigid_family.hpp"
#include "loop/family.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class FluidBodyFamily final : public Family {
 public:
  /// `rigid`: the bodies, or null without; `first_shape_id`: the id of the first shape particle
  /// (ignored without shapes). Built where the scene has fluid and bodies or shapes.
  FluidBodyFamily(const SceneDef& scene, ParticleStore& store, FluidFamily& fluid, RigidFamily* rigid,
                  std::int32_t first_shape_id);

  void add_passes(std::vector<Pass>& passes) override;

  const std::vector<fluid_body::BodyBoundary>& boundaries() const { return boundaries_; }

 private:
  const std::vector<rigid::RigidBody>& bodies() const { return rigid_ ? rigid_->bodies() : no_bodies_; }
  void gather_boundary();
  void solve_density();
  void separate();
  void apply_viscosity();
  /// The boundary's density rho_b,k + rho_s,k of each fluid particle k of `at` (the error
  /// probe's positions) into density[k].
  void measured_boundary_density(const FluidErrorProbe::Positions& at, double* density);
  /// Calls visit(body k, site s, q - site) for every site within reach of world point p (q: p
  /// in body k's frame).
  template <class Visit>
  void for_each_site(rigid::Vec3d p, Visit&& visit) const;
  /// The bodies' grid at their poses now, for the density passes' reach (the boundary's) or the
  /// separation's (the solid's extent + the particle's radius).
  void build_grid(bool separation);

  ParticleStore& store_;
  FluidFamily& fluid_;
  RigidFamily* rigid_;  // null without bodies
  std::vector<rigid::RigidBody> no_bodies_;
  std::unique_ptr<fluid_body::ShapeBoundary> shapes_;  // null without shapes
  std::vector<fluid_body::BodyBoundary> boundaries_;  // per body, scene order
  std::vector<kernels::Float4> boundary_;  // per fluid particle: (g_b,i, rho_b,i)
  std::vector<rigid::Vec3d> kept_;          // per fluid particle: p_i when g_b,i was taken
  double particle_radius_;
  fluid_body::BodyGrid grid_;  // which bodies a particle may reach (body_grid.hpp)
  std::vector<rigid::Vec3d> centres_;
  std::vector<double> reaches_;
  std::vector<rigid::Vec3d> shape_dv_;  // per shape particle with pairs: its viscosity reaction
};

}  // namespace seiche
