// Joints between rigid bodies, XPBD with compliance from connector points (Müller et al. 2020,
// section 3.3; the seed's connector points P = x + R(q) r): every iteration each joint moves its
// two bodies through their generalized inverse masses (body_correction.hpp).
//   ball    P_b - P_a = 0                                  (3 translational degrees locked)
//   hinge   the axes a_a = R_a u_a and a_b = R_b u_b aligned: e = theta (a_a x a_b) / |a_a x a_b|,
//           theta = atan2(|a_a x a_b|, a_a . a_b) (body b turned by e too far); then P_b = P_a.
//           Its angle phi about a_a: the signed angle from b_a = R_a s_a to b_b = R_b s_b
//           (s perpendicular to u, equal in the world at the start, so phi starts at 0):
//           phi = atan2((b_a x b_b) . a_a, b_a . b_b). A limit [lo, hi] corrects e = (phi -
//           clamp(phi, lo, hi)) a_a when phi is outside it; a motor drives phi to a target angle,
//           or to phi_0 + omega_target h each substep (phi_0 its angle when the substep began),
//           e = wrap(phi - target) a_a with the motor's own compliance.
//   fixed   q_b = q_a q_rest (q_rest = q_a^-1 q_b at the start): e = log(q_b (q_a q_rest)^-1);
//           then P_b = P_a.
//   distance  |P_b - P_a| in [min, max] (P_a and P_b each body's own point): when outside, the
//           positional error d = (|d| - clamp(|d|, min, max)) d / |d|, d = P_b - P_a.
//   slider  the orientation as for fixed; then P_b - P_a = s a_a with s in [lower, upper] (or
//           any s without limits): the positional error d - clamp(d . a_a, lower, upper) a_a,
//           s = d . a_a (0 at the start). A motor drives s to a target position, or to
//           s_0 + v_target h each substep (s_0 its position when the substep began): the
//           positional error (s - target) a_a with the motor's own compliance.
//   universal  (a Cardan joint: a cross between two forks) the axis a_a = R_a u_a of body a
//           and a_b = R_b u_b of body b kept perpendicular: with c = a_a x a_b, the error
//           e = -atan2(a_a . a_b, |c|) c / |c| (body b turned by e too far: the angle between
//           the axes is 90 degrees less atan2(a_a . a_b, |c|)); then P_b = P_a. Body b turns
//           with body a about any axis perpendicular to both, and freely about each.
// A body index of -1 is the world (a fixed body at the origin, unrotated), whose "body frame" is
// the world frame.
// With the tree solve on (solver.joint_trees), the joints but the distance joints that form a
// forest are solved first, exactly along their trees (joint_tree.hpp: their equality rows); the
// rest (the distance joints, the joints that close loops, and the limits and motors of the hinges
// and sliders in the trees: a hinge's limit through its anchor, hinge_limit.hpp) are then solved
// by Gauss-Seidel in colours (joint_colours.hpp): the
// joints of one colour share no movable body, and each joint's colour is one more than the
// highest of the earlier joints (scene order) it shares a movable body with, so that solving
// the colours in order gives the bits of the serial solve in scene order, at any thread count.
// A colour of kParallelColour joints or more runs in parallel (TBB), smaller ones serially: a
// joint solve takes about 0.2 us, and 1000 independent hinges took 3.4 ms a frame serially and
// 1.8 ms on 2 threads (8 x 2), where a few dozen gain nothing from a parallel loop's start.
// A joint's parts: its angular constraints first (the paper's order: alignment, limits), then
// the anchor, then a motor's drive, which is what each iteration ends on, so that the joint
// turns (or slides) at the motor's rate while the anchor converges.
#pragma once

#include <span>
#include <vector>

#include "joint_colours.hpp"
#include "joint_tree.hpp"
#include "rigid_body.hpp"

namespace seiche::rigid {

enum class JointType { Ball, Hinge, Fixed, Distance, Slider, Universal };
/// A motor's target: a hinge's angle or a slider's position (Position), or its rate (Velocity).
enum class MotorMode { None, Position, Velocity };

struct Joint {
  JointType type = JointType::Ball;
  int body_a = -1, body_b = -1;  ///< indices into the bodies; -1: the world
  Vec3d anchor_a, anchor_b;      ///< the connector point in each body's frame
  Vec3d axis_a, axis_b;          ///< hinge, slider: the unit axis u in each body's frame;
                                 ///< universal: body a's axis u_a and body b's u_b, each in its frame
  Vec3d normal_a, normal_b;      ///< hinge: a unit s perpendicular to u, in each body's frame
  Quatd rest_rotation;           ///< fixed, slider: q_a^-1 q_b at the start
  double compliance = 0.0;       ///< m/N and rad/(N m)
  bool limited = false;             ///< hinge: angle limits; slider: travel limits
  double lower = 0.0, upper = 0.0;  ///< hinge: rad; slider: m along the axis
  double min_distance = 0.0, max_distance = 0.0;  ///< distance (m)
  MotorMode motor = MotorMode::None;
  double target = 0.0;              ///< hinge: rad or rad/s; slider: m or m/s
  double motor_compliance = 0.0;    ///< hinge: rad/(N m); slider: m/N
  double length = 1.0;  ///< m: the scale of its drift (the reach of its bodies from the anchor)

  // Per substep.
  double motor_start = 0.0;  ///< phi (hinge) or s (slider) when the substep began (Velocity)
  double lambda_position = 0.0, lambda_align = 0.0, lambda_limit = 0.0, lambda_motor = 0.0;
};

/// The joints' solve over `bodies` (the world is the fixed body `world`).
class JointSolver {
 public:
  /// A colour of at least this many joints is solved in parallel, in blocks of kParallelGrain.
  static constexpr std::size_t kParallelColour = 256, kParallelGrain = 64;
  JointSolver() = default;
  /// With `trees`, the joints but the distance joints that form a forest over `bodies` take the
  /// tree solve (a hinge's or slider's limit and motor stay with Gauss-Seidel, after it).
  /// `gravity` sets the load the tree solve expects on its joints (joint_tree.hpp).
  JointSolver(std::vector<Joint> joints, std::span<const RigidBody> bodies, bool trees, Vec3d gravity = {});

  const std::vector<Joint>& joints() const { return joints_; }
  bool empty() const { return joints_.empty(); }

  /// Before the bodies are predicted: each velocity motor's phi_0 or s_0.
  void begin_substep(std::span<const RigidBody> bodies);
  /// Before the first iteration: every multiplier to 0.
  void reset_multipliers();
  /// The tree solve's multipliers, which carry across substeps (the checkpoint's state).
  std::vector<Vec3d> tree_multipliers() const { return trees_.multipliers(); }
  void restore_tree_multipliers(std::span<const Vec3d> lambdas) { trees_.restore_multipliers(lambdas); }
  /// How many joints the tree solve takes.
  std::size_t tree_joints() const;
  /// One iteration: the trees, then every other joint once, colour by colour (and the limits
  /// and motors of the hinges and sliders in the trees).
  void solve(std::span<RigidBody> bodies, double h);
  /// The colours of the joints the tree solve leaves (indices into joints()).
  const JointColours& colours() const { return colours_; }

  /// A joint's errors on the bodies as they are: the length of its positional error (m: |P_b -
  /// P_a|, for a distance joint how far outside its range, for a slider off its axis or range)
  /// and its angular error (rad: the hinge's axis misalignment plus how far phi is outside its
  /// limits; the fixed joint's and slider's rotation off its rest; how far the universal
  /// joint's axes are from perpendicular; 0 for ball and distance).
  struct Error {
    double distance = 0.0;
    double angle = 0.0;
  };
  Error error(const Joint& j, std::span<const RigidBody> bodies) const;

  /// The hinge angle phi of joint j (0 for the other types).
  double hinge_angle(const Joint& j, std::span<const RigidBody> bodies) const;
  /// The slider position s = (P_b - P_a) . a_a of joint j (0 for the other types).
  double slider_position(const Joint& j, std::span<const RigidBody> bodies) const;

 private:
  std::vector<Joint> joints_;
  JointTreeSolver trees_;
  std::vector<char> in_tree_;  // per joint: the tree solve takes it
  JointColours colours_;       // of the others
  RigidBody world_;  // fixed, at the origin, unrotated

  // Hands the joints but the distance joints that form a forest to the tree solve.
  void take_trees(std::span<const RigidBody> bodies, Vec3d gravity);
  // One Gauss-Seidel step of joint k (in a tree: its limit and motor only); inverse_h2 = 1 / h^2.
  void solve_joint(std::size_t k, std::span<RigidBody> bodies, double h, double inverse_h2);
};

/// `angle` wrapped into [-pi, pi].
double wrap_angle(double angle);

}  // namespace seiche::rigid
