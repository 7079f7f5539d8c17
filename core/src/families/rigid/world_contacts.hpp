// Contacts of rigid bodies with the static world (world_surfaces.hpp), with Coulomb friction and
// restitution, after Müller et al. 2020, sections 3.5-3.6.
//
// Contact points, in the body frame, each the centre of a ball of radius rho: a box's 8
// corners (rho = 0), a sphere's centre (rho = its radius), a capsule's two cap centres (rho = its
// radius), a mesh body's vertices (rho = 0: a mesh touches at its vertices only, so a long edge
// or a large face may sink into a sphere or a convex collider between them). A capsule's side,
// which its cap balls miss (one lying across a collider narrower than itself fell through):
//   - against a box collider, capsule_sides.hpp's points of the segment (its crossing of the
//     box's edge, the segment clipped to the face's sides), the box seen as a body at its centre
//     with the world's axes, each a ball of the capsule's radius, one point slot per role;
//   - against a mesh collider, its axis balls: n - 1 balls of its radius at equal steps between
//     the cap centres, n = ceil(length / rho) (steps of at most rho: at a sharp ridge between two
//     balls the capsule sinks by up to (1 - sqrt(3)/2) rho = 0.13 rho), tested against meshes
//     only (and by the body contacts against mesh bodies only);
//   - against a sphere collider, the segment's point closest to its centre, and against a
//     capsule collider, the two segments' closest points (crossed inside both) or else the body
//     segment's points closest to the collider's ends (capsule_sides.hpp; exact: a ball against
//     the collider's solid), the collider seen as a body at its centre with the world's axes,
//     one point slot per role.
// Every iteration, body by body in scene order (serial: the same bits at any thread count),
// with a point's centre c = x + R r_c against each surface its bounding ball (its extent, grown
// by half) reaches:
//   normals: depth d of the ball in the surface, outward normal n (a contact where d > 0); the
//     body's contact point P = c - rho n, lever r = P - x, w = 1/m + (r x n)^T I^-1 (r x n);
//     dlambda_n = d / w (zero compliance), the impulse dlambda_n n at r (body_correction.hpp).
//     All of a body's points from the same pose, applied together (Jacobi), and again until no
//     point is deeper than 1e-12 m (at most 32 passes). A pass in which a capsule's side point
//     (box, sphere or capsule collider) touches scales its impulses by the step s that fits the depths best, as the
//     body contacts do (body_contacts.hpp): with dd_j the change of point j's depth under all the
//     impulses together, s = sum d_j dd_j / sum dd_j^2, at most 1 (two side points near the
//     centre of a capsule pushed it 1.55 times as far as needed, and it bounced every substep);
//     the other passes keep s = 1. One point after the other (the paper's
//     Gauss-Seidel) turns the body at each corner, which the next corner undoes: a resting box
//     then slides on its corners' tangential motion, and its normal multipliers overshoot; a
//     face's corners pushed together move it straight out.
//   static friction, per surface, in the cone of the body and that surface together: with
//     lambda_n the sum of its points' normal multipliers of the substep and lambda_t the vector
//     sum of the friction impulses so far, a correction is applied only where
//     |lambda_t + its impulse| < mu_s lambda_n. The slip of a body point since the substep began:
//     dp = P - P_prev (P_prev = x_prev + R(q_prev) r_local; the world does not move),
//     dp_t = dp - (dp.n) n, t = dp_t / |dp_t|.
//     - A face (3 points or more on the surface) cannot tip: its normals hold it. One constraint
//       at the points' centre (weighted by their lambda_n), which moves the body along the
//       surface and turns it about n only: w_t = 1/m + ((r x t).n)^2 n^T I^-1 n, the impulse
//       -|dp_t| / w_t t. Then its turn about n since the substep began, theta = n.log(q q_prev^-1),
//       undone by the angular impulse -theta / (n^T I^-1 n) where its sum stays below
//       mu_s lambda_n rho_patch (rho_patch: the points' weighted mean distance from the centre).
//     - Else (a ball, an edge, a corner) each touching point's impulse -|dp_t| / w_t t (w_t as w,
//       along t), all from the same pose, applied together.
//   (lambda_n, lambda_t and the twist are reset when a substep begins.)
// After the velocity update (v, omega from the positions), per surface the body touched in the
// substep (lambda_n > 0), with v_c = v + omega x r at a point, v_n = v_c.n, v_t = v_c - v_n n:
//   restitution, point by point: dv = n (-v_n + max(-e vbar_n, 0)), vbar_n = n.(vbar + omegabar x r)
//     from the velocities before the substep; e = 0 where |vbar_n| <= 2 |g| h (a body at rest
//     gains g h a substep: no bounce from that, no jitter); applied as the impulse p = dv / w
//     (w along dv): v += p / m, omega += I^-1 (r x p).
//   dynamic friction (the paper's eq. 30, as an impulse): the speed change along -v_t is
//     min(mu_d lambda_n w_t / h, |v_t|): the impulse mu_d lambda_n / h (mu_d times the substep's
//     normal impulse) at most. A face at its centre with its w_t (above), and its spin about n
//     slowed by at most mu_d lambda_n rho_patch n^T I^-1 n / h; else point by point with its own
//     lambda_n.
// Materials: the body's static friction mu_s, dynamic mu_d and restitution e; a surface has one
// Coulomb coefficient mu_c (the domain's or the collider's `friction`), mixed with the body's as
// the geometric mean, mu = sqrt(mu_body mu_c): a frictionless side (0) gives no friction, equal
// coefficients give that coefficient.
#pragma once

#include <utility>
#include <vector>

#include "box_box.hpp"
#include "rigid_body.hpp"
#include "seiche/scene.hpp"
#include "world_surfaces.hpp"

namespace seiche::rigid {

/// One contact point of a body: the centre of a ball in the body frame, and its radius.
struct ContactPoint {
  Vec3d centre;
  double radius = 0.0;
};

/// The contact points of `def`'s shape (above).
std::vector<ContactPoint> contact_points(const RigidBodyDef& def);
/// A capsule's balls inside its segment, for its side against a mesh (above): n - 1 balls of its
/// radius rho at equal steps between the cap centres, n = ceil(length / rho); none for the other
/// shapes (or a capsule no longer than its radius).
std::vector<ContactPoint> capsule_axis_points(const RigidBodyDef& def);

class WorldContacts {
 public:
  WorldContacts() = default;
  /// The scene's bodies (their points and materials, in scene order) against its static world
  /// (`mesh_fields`: its mesh colliders' fields, WorldSurfaces).
  WorldContacts(const SceneDef& scene, double substep, std::span<const std::shared_ptr<const MeshSdf>> mesh_fields);

  /// Before the bodies' predict: their velocities before the substep (for restitution), and the
  /// multipliers reset.
  void begin_substep(const std::vector<RigidBody>& bodies);
  /// One iteration of the positional pass (normal and static friction).
  void solve_positions(std::vector<RigidBody>& bodies);
  /// After the velocity update: dynamic friction and restitution.
  void solve_velocities(std::vector<RigidBody>& bodies);
  /// Per body: whether a surface has held it up in this substep so far: a point with a normal
  /// multiplier > 0 whose normal n has n.up > min_cosine (a wall or a ceiling does not hold it).
  void held_up(std::vector<char>& out, Vec3d up, double min_cosine) const;

 private:
  struct Material {
    double static_friction = 0.0, dynamic_friction = 0.0, restitution = 0.0;
  };
  struct Slot {  // one (body, point, surface) within a substep
    double lambda_n = 0.0;
    bool touching = false;  // in this iteration
    Vec3d normal;
    Vec3d local;  // the body's contact point P, body frame
  };
  struct Pair {  // one (body, surface) within a substep
    double lambda_n = 0.0;  // the sum of its points' normal multipliers
    Vec3d lambda_t;         // the sum of their static friction impulses (vector)
    double twist = 0.0;     // a face's static friction about the normal (angular impulse)
  };
  struct Patch {  // a face of a body on a surface
    Vec3d centre;  // its points' centre weighted by their normal multipliers, body frame
    Vec3d normal;
    double radius = 0.0;  // rho: its points' mean distance from the centre, weighted the same
  };
  struct Touch {  // one point's normal in one pass: slot (point, surface), lever r, dlambda_n = d / w
    int point = 0, surface = 0;
    Vec3d r, normal;
    double depth = 0.0, dlambda = 0.0;
  };
  /// The step s that fits the pass's depths best (touches_ from body b's pose; body_contacts.hpp).
  double best_step(const RigidBody& b) const;
  /// A face: 3 points or more of `body` on `surface` (touching in this iteration, or in the
  /// substep), and their centre.
  bool face_patch(std::size_t body, int surface, bool this_iteration, Patch& out);
  Slot& slot(int point, int surface) {
    return slots_[std::size_t(point) * std::size_t(surfaces_.count()) + std::size_t(surface)];
  }
  Pair& body_surface(std::size_t body, int surface) {
    return pairs_[body * std::size_t(surfaces_.count()) + std::size_t(surface)];
  }

  WorldSurfaces surfaces_;
  // A box, sphere or capsule collider as a body: its centre, the world's axes, the solid about it.
  struct ColliderFrame {
    RigidBody frame;
    SolidSurface solid;
  };
  std::vector<ContactPoint> points_;      // every body's, body after body (a capsule's side roles last)
  std::vector<int> first_point_;          // per body, into points_; one more entry at the end
  std::vector<Material> materials_;       // per body
  std::vector<double> extent_;            // per body: its farthest point from the centre (m)
  std::vector<int> first_axis_point_;     // per body: its axis balls' first point (a capsule's; else
                                          // its side roles' or the end: none)
  std::vector<int> first_side_point_;     // per body: its side roles' first point (a capsule), else -1
  std::vector<SolidSurface> capsule_solid_;  // per body: its solid in its frame (a capsule's only)
  std::vector<ColliderFrame> collider_frames_;  // per surface: a box, sphere or capsule's (others unused)
  std::vector<char> near_;                // per surface: the body now within reach of it
  std::vector<Vec3d> v_before_, omega_before_;  // per body, at the start of the substep
  std::vector<Slot> slots_;
  std::vector<Pair> pairs_;
  std::vector<Touch> touches_;  // scratch: one pass's normals of one body
  std::vector<std::pair<Vec3d, Vec3d>> friction_;  // scratch: (lever, impulse) of one surface's points
  double h_ = 0.0;
  double rest_speed_ = 0.0;  // 2 |g| h
};

}  // namespace seiche::rigid
