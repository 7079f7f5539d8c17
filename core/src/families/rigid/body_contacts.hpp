// Contacts between rigid bodies, with Coulomb friction and restitution, after Müller et al.
// 2020, sections 3.5-3.6, as the contacts with the static world (world_contacts.hpp) do them, but
// with two bodies moving: every correction is an impulse p on body a at lever r_a and -p on body b
// at r_b, and every inverse mass the sum w = w_a + w_b (body_correction.hpp).
//
// Narrow phase: two boxes by separating axes and clipping, face against face or edge against
// edge (box_box.hpp), each point in the pair's slot of its features (below). Any other pair:
// each body's contact points (world_contacts.hpp: a sphere's centre with its radius, a capsule's
// cap centres with its radius, box corners, a mesh's vertices, a capsule's axis balls against a
// mesh body only; and here a mesh's large triangles,
// area above (extent / 8)^2, each corner moved a third of the way to the centroid, radius 0:
// equal mesh cubes stacked meet vertex on vertex, where a vertex lies on the lower body's side
// as much as under its top, so the nearest face is the side and the depth 0, and they fell
// through; points inside the faces hold them) against the other body's solid
// (world_surfaces.hpp's penetration() on body_solid.hpp: box, sphere, capsule, or the closed
// mesh's signed distance field in its body frame), the point moved into that body's frame, both
// ways per pair; and a capsule's side against a capsule or a box (capsule_sides.hpp: the
// segments' crossing, the segment across a box's face or edge), one slot per role. A ball
// against a solid is exact: sphere-sphere, sphere-capsule, and capsule-capsule end on or side by
// side. Known limits: a capsule's side on a mesh body rests on its axis balls (steps of at most
// its radius: at a sharp ridge between two of them it sinks by up to 13 % of its radius); a mesh
// touches at its vertices, the normal from the other body's nearest face point by point.
// Slots: a point's normal multiplier is summed in its slot over the substep's passes and
// iterations, and read by friction and restitution at that point, so a slot keeps one point: a
// ball's slot is its body's contact point, a box pair's is keyed by the touching features
// (box_box.hpp; numbered in clip order, a slot handed one corner's impulse to another when a
// point left the clip or a depth of 1e-17 came and went). A box pair has 16 slots; where a
// substep finds more features, a slot whose feature touched in no pass of this iteration is taken
// over (its state dropped). When the reference face changes, the features are new, so their
// slots start from zero (the old ones keep what they carried, at their points).
// For a's ball (centre c, radius rho) reaching depth d into b along b's outward normal m: the
// normal n = m (the way a is pushed), a's point P_a = c - rho m, b's point P_b = P_a + d m; b's
// ball into a: n = -m, P_b = c - rho m, P_a = P_b + d m.
//
// Broad phase, once a substep on the predicted poses: every pair of bodies not joined by a joint
// nor in one articulation (rigid_family.cpp) and not both fixed whose bounding balls (their
// extents), grown by what they move in a substep ((|v_a| + |v_b|) h), overlap, visited in a fixed
// order: from the lowest (along -gravity, the lower of the pair's two centres) up, ties in the
// pairs' order. Serial: the same bits on any
// thread count. A scene with no such pair does nothing more.
//
// Per iteration, pair by pair in that order (Gauss-Seidel across pairs, Jacobi within a pair; a
// pass's impulses are summed and applied at once, one move per body, so no order among them):
//   normals: all of the pair's points from the same poses, dlambda_i = d_i / w_i, scaled by the
//     step s that fits the depths best: with dd_j the change of point j's depth under all the
//     impulses together (the bodies' linear response), s = sum d_j dd_j / sum dd_j^2, at most 1.
//     A face seen from both sides would otherwise be pushed twice as far, and the passes would
//     swing; a single point keeps s = 1. Again until no point is deeper than 1e-12 m (at most 32
//     passes).
//   static friction, in the cone of the pair, |lambda_t| < mu_s lambda_n, with the relative slip
//     of two contact points since the substep began, dp = (P_a - P_a,prev) - (P_b - P_b,prev)
//     (each from its body-frame point and its body's pose at the start):
//     - a face (3 points or more) as the world's face: one constraint at the points' centre
//       (weighted by lambda_n) that moves the bodies along the surface and turns them about n
//       only, w_t = sum over the two of 1/m + ((r x t).n)^2 n^T I^-1 n; then the relative turn
//       about n since the substep began undone within mu_s lambda_n rho. Friction at the corners,
//       below the centre of mass, tipped each box of a 10-box stack a little, and the stack
//       amplified it until it fell (measured); the face's constraint cannot tip.
//     - else each point's impulse -|dp_t| / w_t t (t = dp_t / |dp_t|), with the best step.
//   Stacks (shock propagation, Guendelman et al. 2003): a pair whose pushing direction (its
//     normals weighted by their depths) is within 45 degrees of the vertical, with its lower body
//     resting (the world held it up in this substep: a contact whose normal is within 45 degrees
//     of the vertical, not a wall's nor a ceiling's; or it rests on a resting body, found in this
//     same bottom-up order), treats that lower body as fixed (w = 0, not moved): the ground
//     carries what lands on it. Without it, the weight above reaches the floor only over many
//     iterations: scenes/stack.json sank into itself (the top box by 0.95 mm) and drifted
//     sideways by up to 3.5 mm in 10 s at the defaults (measured). A pair in the air, or side by
//     side, keeps both masses: its momentum is conserved. Never against a fixed upper body: a
//     resting body pressed up into a fixed slab keeps its mass (frozen, the pair had none, and
//     its overlap stayed). A box thrown up along a wall into a slab, which rested when any
//     contact with the world counted, went through the slab, fixed or held by a joint.
// After the velocity update, per touching pair (the lower body again fixed where the positions
// treated it so), with v_rel = (v_a + omega_a x r_a) - (v_b + omega_b x r_b) at each point:
//   restitution: every point's normal speed change dv = -v_n + max(-e vbar_n, 0) at once (vbar_n
//     from the velocities before the substep; e = 0 where |vbar_n| <= 2 |g| h), with the best
//     step, until none is off by more than 1e-12 m/s.
//   dynamic friction: each point's speed change along -v_t, min(mu_d lambda_n w_t / h, |v_t|), at
//     once with the best step.
// Materials: static and dynamic friction mixed as the world contacts mix them, the geometric mean
// sqrt(mu_a mu_b); restitution the larger of the two bodies' (a world surface's is 0, so against
// the world the body's own counts, as here against a body of restitution 0).
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "body_solid.hpp"
#include "rigid_body.hpp"
#include "seiche/scene.hpp"
#include "world_contacts.hpp"
#include "world_surfaces.hpp"

namespace seiche::rigid {

class BodyContacts {
 public:
  BodyContacts() = default;
  /// The scene's bodies; `jointed`: the pairs of body indices that never touch (rigid_family.cpp:
  /// joined by a joint, or in one articulation).
  BodyContacts(const SceneDef& scene, const std::vector<std::pair<int, int>>& jointed, double substep,
               BodyMeshFields& mesh_fields);

  /// No pair of bodies can touch: nothing to do.
  bool empty() const { return candidates_.empty(); }
  /// Before the bodies' predict: their velocities before the substep, the multipliers reset.
  void begin_substep(const std::vector<RigidBody>& bodies);
  /// One iteration of the positional pass; `world` tells which bodies the static world held up in
  /// this substep (they rest: shock propagation).
  void solve_positions(std::vector<RigidBody>& bodies, const WorldContacts& world);
  /// After the velocity update: restitution and dynamic friction.
  void solve_velocities(std::vector<RigidBody>& bodies);

 private:
  struct Body {
    int first_point = 0, end_point = 0;  // into points_
    int first_axis_point = 0;            // a capsule's axis balls (against a mesh only) up to end_point
    SolidSurface solid;                  // body frame (body_solid.hpp)
    double extent = 0.0;
    double static_friction = 0.0, dynamic_friction = 0.0, restitution = 0.0;
  };
  struct Slot {  // one point of one body of an active pair, within a substep
    int point = 0;
    bool of_a = true;   // a's point in b's solid, else b's in a's
    int feature = -1;   // two boxes: the features that touch there (box_box.hpp); -1: none yet
    std::uint32_t stamp = 0;  // two boxes: the normal pass that last found that feature
    bool touching = false;
    double lambda_n = 0.0;
    Vec3d normal;       // world: the way a is pushed
    Vec3d local_a, local_b;  // the contact points in their bodies' frames
  };
  struct Active {  // a pair near enough in this substep
    int a = 0, b = 0;
    int candidate = 0;  // its index in candidates_ (the order of ties)
    int first_slot = 0, end_slot = 0;
    int first_side_slot = 0;  // the slots from here on: a capsule's side (capsule_sides.hpp)
    double height = 0.0;    // the lower centre along -gravity
    int fixed = 0;          // shock propagation in the last normal pass: 1 a, 2 b treated as fixed, 0 neither
    double lambda_n = 0.0;  // the sum of its points' normal multipliers
    Vec3d lambda_t;         // the sum of its static friction impulses
    double twist = 0.0;     // a face's static friction about the normal (angular impulse)
  };

  struct Touch {  // one point's correction in a pass: the impulse dlambda along `normal` (on a;
                  // -that on b), to change the points' relative position or velocity by `depth`
    int slot = 0;
    Vec3d r_a, r_b;  // the levers of the two contact points, world frame
    Vec3d normal;
    double depth = 0.0, dlambda = 0.0;
  };

  void find_pairs(const std::vector<RigidBody>& bodies);
  struct Sums {  // the touches' impulses summed: on a; b gets the opposite
    Vec3d impulse, moment_a, moment_b;  // sum p, sum r_a x p, sum r_b x p
  };
  Sums sums(double step) const;
  /// Static friction of a face (3 touching points or more) as the world contacts do it: false
  /// where the pair has no face.
  bool face_friction(Active& pair, RigidBody& a, RigidBody& b, double mu_s);
  /// The share s in [0, 1] of the touches' impulses that best resolves their depths together.
  double best_step(const RigidBody& a, const RigidBody& b, int fixed) const;
  /// The touches' impulses times `step`, summed and applied at once (no order between them): to
  /// the positions, x += sum p / m, q turned by I^-1 sum r x p; or to the velocities.
  void apply_positions(RigidBody& a, RigidBody& b, double step, int fixed) const;
  void apply_velocities(RigidBody& a, RigidBody& b, double step, int fixed) const;
  void solve_pair(Active& pair, RigidBody& a, RigidBody& b);
  /// Two boxes: the slot of the pair that holds `feature` in this substep; else a free one, else
  /// one whose feature touched in no pass of this iteration (its state dropped), claimed for it;
  /// -1 where none is left.
  int feature_slot(const Active& pair, int feature);

  std::vector<Body> bodies_;
  std::vector<ContactPoint> points_;
  std::vector<std::shared_ptr<const MeshSdf>> mesh_sdfs_;  // the mesh bodies' fields
  std::vector<std::pair<int, int>> candidates_;            // pairs that may touch, a < b
  std::vector<Active> active_;
  std::vector<Slot> slots_;
  std::vector<char> resting_;  // per body, within an iteration: fixed, on the world or on a resting body
  std::vector<double> reach_;  // per body, within find_pairs: its extent + |v| h
  std::vector<Vec3d> v_before_, omega_before_;
  std::vector<Touch> touches_;  // scratch: one pass's impulses
  Vec3d up_;                // -gravity, unit (zero without gravity)
  bool pairs_found_ = false;  // in this substep
  double h_ = 0.0;
  double rest_speed_ = 0.0;  // 2 |g| h
  std::uint32_t pass_stamp_ = 0;  // counts the normal passes of box pairs (Slot::stamp; wraps)
};

}  // namespace seiche::rigid
