// Two-way contacts of cloth and shape-matched particles with rigid bodies: a particle's ball (its
// collision radius: half a cloth's thickness, half a shape's spacing) is pushed out of a body's
// solid (box, sphere, capsule, closed mesh: the queries of world_surfaces.hpp, asked in the
// body's frame), and the body is pushed back at the contact point through its generalized inverse
// mass (body_correction.hpp). XPBD with zero compliance, one constraint per contact:
//   p_l = R(q)^T (p - x)          the particle's centre in the body frame
//   d, n_l = penetration of the ball (p_l, r) into the solid;  n = R(q) n_l  (out of the body)
//   lever  s = p - (r - d) n - x   (the body's surface point under the ball, from its centre)
//   w_b = 1/m + (s x n)^T I^-1 (s x n),  w_p = the particle's inverse mass
//   lambda = d / (w_p + w_b)
//   p += w_p lambda n;  the body gets the impulse -lambda n at s (x -= lambda n / m, q turned by
//   I^-1 (s x -lambda n)): linear momentum is unchanged (m_p dp + m_b dx = 0).
// Friction, as the colliders do for particles (kernels/collisions.hpp), on the motion relative to
// the body: the slip of the substep u = (p - x_p) - (P - P_prev), P = x + R(q) s_l and
// P_prev = x_prev + R(q_prev) s_l the body point under the ball now and when the substep began
// (s_l = R(q)^T s), tangential u_t = u - (u.n) n, t = u_t / |u_t|:
//   keep = 1 where |u_t| <= mu d (static: the particle sticks to the body), else mu d / |u_t|
//   lambda_t = keep |u_t| / (w_p + w_b(t));  p -= w_p lambda_t t;  the body gets +lambda_t t at s.
// mu: a cloth's `friction` mixed with the body's static `friction` as sqrt(mu_cloth mu_body) (as
// the bodies' world contacts mix theirs); a shape's particle, which has no coefficient of its own,
// takes the body's.
//
// Candidates: once per substep (Neighbors stage, after the bodies' predict and the fluid's
// reorder), every cloth and shape particle whose predicted ball, grown by 3 of its radii and a
// tenth of the body's extent (what the particle and the body may move in the iterations), reaches
// into the body's solid, in store order, body by body in scene order.
// The solve, every iteration after the shape matching and before the joints and the bodies' world
// contacts (pass_order::kParticleBodyContacts), goes through the list serially, Gauss-Seidel in
// that fixed order: the same bits at any thread count. Nothing is carried across substeps (the
// list is rebuilt, the multipliers of zero compliance are not needed), so checkpoints hold nothing
// new. Built only for a scene with bodies and cloth or shapes: any other scene pays nothing.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "loop/family.hpp"
#include "body_solid.hpp"
#include "rigid_body.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"
#include "world_surfaces.hpp"

namespace seiche {

class ParticleBodyContacts final : public Family {
 public:
  /// A particle is a candidate of a body when its ball, grown by kReachRadii of its radii and
  /// kReachFraction of the body's extent, reaches into the body's solid (a mesh body: into the
  /// ball of its extent grown so).
  static constexpr double kReachRadii = 3.0;
  static constexpr double kReachFraction = 0.1;

  /// Whether `scene` needs it: rigid bodies, and cloth or shapes.
  static bool needed(const SceneDef& scene);

  /// `bodies`: the rigid family's bodies (scene order), moved by the contacts.
  ParticleBodyContacts(const SceneDef& scene, ParticleStore& store,
                       std::vector<rigid::RigidBody>& bodies, rigid::BodyMeshFields& mesh_fields);

  void add_passes(std::vector<Pass>& passes) override;

  /// The candidate pairs of this substep (for tests): particle store index and body index.
  struct Candidate {
    std::uint32_t particle;
    std::uint32_t body;
  };
  const std::vector<Candidate>& candidates() const { return candidates_; }

 private:
  void find_candidates();
  void solve();

  struct Solid {  // one body's, in its own frame
    rigid::SolidSurface surface;
    double extent = 0.0;  // its farthest point from the centre (m)
  };
  ParticleStore& store_;
  std::vector<rigid::RigidBody>& bodies_;
  std::vector<Solid> solids_;                              // per body
  std::vector<std::shared_ptr<const MeshSdf>> mesh_sdfs_;  // the mesh bodies' fields
  std::vector<double> body_friction_;                      // per body: static mu
  std::vector<double> cloth_friction_;                     // per cloth
  std::vector<Candidate> candidates_;
};

}  // namespace seiche
