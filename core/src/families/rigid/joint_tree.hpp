// The exact solve of the ball, hinge, fixed, slider and universal joints (their equality rows)
// along spanning trees of the bodies, per iteration: Baraff 1996 ("Linear-time dynamics using
// Lagrange multipliers") with 6 x 6 body blocks and joint blocks of m rows (ball 3, universal 4,
// hinge 5, slider 5, fixed 6), as a position-level XPBD step
// (Deul et al. 2018). A chain of 1:1000 mass ratio hangs as stiffly as one of equal links, where
// one Gauss-Seidel sweep moves a load about one joint and lets the heavy end stretch the chain
// (the particles' version: kernels/distance_tree.hpp).
//
// One iteration solves the linearization at the current positions (a tree on the start
// directions, below: its rows' directions and inertia at the start of the substep), for all
// joints e of the forest at once:
//   M_v dx_v = sum_{e at v} J_ev^T dlambda_e                          (every body v)
//   sum_v J_ev dx_v + alpha~_e dlambda_e = b_e := -C_e - alpha~_e lambda_e   (every joint e)
// dx_v = (dp, dtheta) the body's move and world rotation vector, M_v = diag(m I, I_world),
// alpha~ = compliance / h^2 (every row of the joint), lambda_e an m-vector. The rows of C_e:
//   positional (all but the slider)  P_b - P_a (P = x + r, r = R(q) anchor),
//     J_eb = [I, -[r_b]x], J_ea = [-I, [r_a]x] (so M^-1 J^T p is the impulse p at P:
//     x += p / m, dtheta = I^-1 (r x p), as body_correction.hpp);
//   slider (2 positional rows, across its axis)  t_k . (P_b - P_a), t_k as the hinge's below;
//     J_eb = [t_k^T, (r_b x t_k)^T], J_ea = -[t_k^T, ((P_b - x_a) x t_k)^T] (t_k turns with body
//     a, so both act at P_b: body b's point slides along the axis freely); then the fixed
//     joint's 3 angular rows;
//   hinge (2 angular rows)  t_k . e, e = the rotation vector turning a_a = R_a u_a onto
//     a_b = R_b u_b (joint.hpp), t_1 = R_a s_a, t_2 = R_a (u_a x s_a) (perpendicular to a_a,
//     turning with body a); J_eb = [0, t_k^T], J_ea = [0, -t_k^T] (to first order a turn of b
//     about t_k turns e by it, one about a_a leaves e alone);
//   fixed (3 angular rows)  e = log(q_b (q_a q_rest)^-1) (joint.hpp); J_eb = [0, I], J_ea = [0, -I];
//   universal (1 angular row)  -atan2(a_a . a_b, |c|), c = a_a x a_b (the angle between the axes
//     less 90 degrees), J_eb = [0, n^T], J_ea = [0, -n^T], n = c / |c| (t_1 where the axes are
//     parallel).
// With the bodies and joints a forest, eliminating from the leaves to the roots makes no
// fill-in. Body v with parent joint e (its parent p: a body, or fixed) and child joints c
// (child body w), leaves first:
//   K_v = M_v + sum_c J_cv^T D_c^-1 J_cv,   r_v = sum_c J_cv^T s_c                  (6 x 6, SPD)
// (M_v plus the geometric stiffness below),
//   G = K_v^-1 J_ev^T,  u = K_v^-1 r_v,  D_e = J_ev G + alpha~_e I,  s_e = D_e^-1 (b_e - J_ev u)
// then from the roots down (a free root: dx = K^-1 r; a fixed parent: dx_p = 0):
//   dlambda_e = s_e - D_e^-1 J_ep dx_p,   dx_v = G dlambda_e + u,   lambda_e += dlambda_e,
// and last every body moves: x += dp, q += 1/2 [dtheta, 0] q, normalized (rotate_by_small).
// For one joint to the world it is the m-row XPBD step dlambda = (J M^-1 J^T + alpha~)^-1 b.
// A hinge's or slider's limits and motor are not rows: an inequality switched on and off from
// iteration to iteration, and a drive with its own compliance, do not fit a fixed set of equality
// rows. The tree takes such a joint's equality rows, and Gauss-Seidel corrects its limit and motor
// after the tree (joint.hpp; a hinge's limit through its anchor, hinge_limit.hpp). That holds
// scenes/ragdoll_in_cloth.json's elbows and knees within 1.8e-4 of their length, 3.9 mm with the
// hinges on Gauss-Seidel; it does not hold a 1:1000 chain whose load drives every hinge into its
// limit (docs/design.md: nor does Gauss-Seidel alone, nor did the limit as an active row here).
//
// Geometric stiffness. The linearization has no first-order stiffness of a body's rotation at
// a loaded connector, so where a light body carries a large load (a 4 g link under a 4 kg end,
// T h^2 / (m l) about 1 at 8 substeps of 1/60 s) one step turns it far, and the chain gains
// energy and flies apart. As for the particles' forests (Andrews, Teichmann and Kry 2017), K_v
// gets the tension part of lambda . d^2 P / d theta^2 at each of its connectors,
//   K_v += k (I - r r^T / |r|^2)   on the rotation block,   k = max(f . r, 0),
// f the impulse of the joint's positional rows on the body at lever r (+lambda on body_b,
// -lambda on body_a; a slider's lambda_1 t_1 + lambda_2 t_2, at lever P_b - x_a on body a) at
// the end of the previous substep (these impulses carry across substeps: the checkpoint holds
// them). Uncapped, unlike the particles' gamma: a cap at 4 times
// the body's smallest moment of inertia left the 1:1000 chain flying apart at 8 x 2; uncapped it
// holds (and gains no energy) from 1 substep of 1 iteration per 1/60 s up. The angular rows add
// none: at the solution (e = 0) the second derivative of a rotation-vector error is its
// commutator term 1/2 dtheta_a x dtheta_b, antisymmetric, so lambda . d^2 C / d theta^2 has no
// symmetric (stiffness) part.
// Line search. The step (dx, dlambda) of each tree is scaled by the first beta of 1, 1/2, ...,
// 1/16 that decreases the particles' merit (distance_tree.hpp, safeguard 2) enough (Armijo 0.1),
//   phi(beta) = beta^2/2 (sum_v dx_v^T M_v dx_v + sum_e alpha~_e |dlambda_e|^2)
//               + sum_e |dlambda_e| |C_e(x + beta dx) + alpha~_e (lambda_e + beta dlambda_e)|
// (|.| over all m rows); a tree along which no step decreases phi is left as it is.
//
// Start directions (SHAKE). Linearized at the current positions, the step puts each joint's
// impulse along its rows' directions at the end of the substep, as backward Euler does, and
// dissipates in proportion to the substep: a double pendulum of two 0.5 m boxes let go from
// horizontal loses 9.8 % of its energy over 10 s at 8 substeps x 2 iterations. A tree whose
// bodies carry little load for their inertia takes instead the rows' directions (the levers r,
// the hinge's t_k) and the bodies' world inertia at the start of the substep (q_prev), the
// errors C_e still at the current positions, and no geometric stiffness: SHAKE (Ryckaert,
// Ciccotti and Berendsen 1977), symplectic, its energy error bounded (0.069 % on that pendulum,
// 0.080 % on a triple one of 0.3 m capsules). Explicit in the directions, it holds only while a
// body's geometric stiffness is small against its inertia, and its energy oscillates where the
// implicit step's only falls: along them the 1:1000 chain flies apart, the joints of a
// 100-link chain open by 1.4 links, the Y of 1:100 gains 7 % of m g L back after lows. So a tree takes the start
// directions in a substep only where every body's
//   load = sum over its connectors of |f| |r| (tr I^-1 - n^T I^-1 n),  n = r / |r|
// (the trace of I^-1 K_geo with k = |f| |r|: a bound of the geometric stiffness over the
// inertia) is below 0.6, f the larger of the joint's positional multiplier at the end of the
// previous substep (the geometric stiffness's, in the checkpoint) and 3 |g| h^2 times the mass
// of the subtree it carries (a pendulum let go from horizontal pulls 3 m g at the bottom; it
// keeps a tree that is about to carry a load on the end directions while its multipliers are
// still 0). Measured at 8 x 2: the double pendulum 0.03 at most, the triple 0.3; the Y at least
// 1.3, the 100-link chain 2.9, the 1:1000 chains 30. And only where no Gauss-Seidel correction
// acts on the tree's bodies (a loop's closing joint, a distance joint, a hinge's or slider's limit
// or motor: Gauss-Seidel after the tree and the start directions together gained 1.1 % of m g L
// on the ring) and every joint of the tree is a ball, hinge or fixed joint (the types measured;
// joint.cpp decides both). The test reads
// only the multipliers and the scene, so the bits do not depend on the thread count and a
// resumed run goes on bit for bit; a tree on the end directions runs the operations it ran
// before.
//
// The forest: the graph of the movable bodies and one ground node (the world and every fixed
// body), over every joint but the distance joints in scene order; a joint that closes a loop
// (through the ground too: a chain hung at both ends) is left out, and it and the distance joints
// keep the iterative solve (joint.hpp), which runs after this one. A tree per joint to the
// ground (the ground is fixed, so they are independent), then one per piece that does not reach
// it, rooted at its lowest-numbered body; inside a tree breadth first, children in scene order.
// Serial, one fixed order: the bits do not depend on the thread count. A forest of ball joints
// only runs the operations it ran before the other types joined, in the same order (the same bits).
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "rigid_body.hpp"

namespace seiche::rigid {

/// The joint types the tree solve takes, and their equality rows: ball 3 positional; hinge 3 + 2
/// angular; fixed 3 + 3; slider 2 positional (across its axis) + 3 angular; universal 3 + 1.
enum class TreeJointType { Ball, Hinge, Fixed, Slider, Universal };

/// A joint as the tree solve sees it (joint.hpp's Joint; a hinge's or slider's limits and motor
/// are not in it).
struct TreeLink {
  TreeJointType type = TreeJointType::Ball;
  int body_a = -1, body_b = -1;  ///< indices into the bodies; -1: the world
  Vec3d anchor_a, anchor_b;      ///< the connector point in each body's frame
  Vec3d axis_a, axis_b;          ///< hinge, slider: the unit axis u in each body's frame; universal: u_a, u_b
  Vec3d normal_a;                ///< hinge, slider: a unit s_a perpendicular to u_a, in body a's frame
  Quatd rest_rotation;           ///< fixed, slider: q_a^-1 q_b at the start
  double compliance = 0.0;       ///< m/N and rad/(N m)
};

/// The rotation vector that turns unit u onto unit v (zero when they are parallel).
Vec3d rotation_between(Vec3d u, Vec3d v);

class JointTreeSolver {
 public:
  JointTreeSolver() = default;
  /// The forest over the `links` in their order, with `bodies` (which are fixed) under `gravity`.
  JointTreeSolver(std::span<const TreeLink> links, std::span<const RigidBody> bodies, Vec3d gravity = {});
  /// The tree that holds `body` keeps the end-of-step directions: a joint of the iterative
  /// solve acts on the body (the links that close loops mark theirs themselves).
  void keep_end_directions_at(int body);

  bool empty() const { return nodes_.empty(); }
  /// Whether link k is in the forest (else the iterative solve keeps it).
  bool in_forest(std::size_t k) const { return in_forest_[k] != 0; }

  /// Before the first iteration of a substep: every multiplier to 0 (the last ones kept for the
  /// geometric stiffness).
  void reset_multipliers();
  /// The multipliers now (the checkpoint's state): each node's positional impulse (its positional
  /// rows' multipliers; a slider's as a world vector), then the angular rows of each node that has
  /// them (a hinge's two and a universal joint's one padded with 0), and their restore.
  std::vector<Vec3d> multipliers() const;
  void restore_multipliers(std::span<const Vec3d> lambdas);
  /// One iteration: the exact step above over every tree.
  void solve(std::span<RigidBody> bodies, double h);

 private:
  using Mat6 = std::array<double, 36>;  // row-major
  using Vec6 = std::array<double, 6>;
  static constexpr int kMaxRows = 6;
  using Rows = std::array<double, kMaxRows>;  // a joint's m rows, the rest unused
  using Block = std::array<double, 36>;        // up to 6 x 6, row-major, rows of the block's width
  struct Node {
    int body = 0;
    int parent = -1;        ///< position of the parent body's node; -1: a root (fixed parent or free)
    int link = -1;          ///< the parent joint (into links_); -1: a free root
    bool body_is_b = true;  ///< the body is the link's body_b
    int rows = 3;           ///< the parent joint's row count m
    int positional = 3;     ///< how many of them are positional (the rest angular): 3, a slider's 2
    Rows lambda{};          ///< the parent joint's multiplier (N s^2 and N m s^2), within a substep
    Vec3d impulse;          ///< a slider's: the world impulse of its 2 positional rows now (N s^2)
    Vec3d previous_lambda;  ///< its positional rows (a slider's: that impulse) at the end of the previous substep
    double lever_own = 0.0;     ///< w = |r| (tr I^-1 - n^T I^-1 n) of the body at its parent joint
    double lever_parent = 0.0;  ///< the same of the parent body at that joint (0: the ground)
    double swing_force = 0.0;   ///< 3 |g| times the mass of the node's subtree (N)
  };
  // Per node, rebuilt every solve.
  struct Work {
    Mat6 k;       // K_v, then its Cholesky factor
    Vec6 r, u, dx;
    Block g;      // G = K_v^-1 J_ev^T (6 x m)
    Block jp;     // J_ep (m x 6); unused for a fixed parent
    Block d_inv;  // D_e^-1 (m x m)
    Rows s;
    Rows b, dlambda;  // b_e, and the step of lambda_e
    double alpha = 0.0;
    Vec3d across[2];   // a slider's t_1, t_2 at the linearization
    Vec3d x0;          // the body before the step (the line search)
    Quatd q0;
    double load = 0.0;  // trace(I^-1 K_geo) of the body (start directions' test)
    bool start = false;  // its tree takes the start-of-substep directions this substep
  };

  // Node i's step leaves to roots, its parent joint of m rows between bodies a and b (K_v
  // factored, u known): G, D^-1, s and the parent's K and r; false where D is not positive
  // definite.
  template <int m>
  bool eliminate(std::size_t i, const RigidBody& a, const RigidBody& b, double inverse_h2, bool start);
  // Whether tree t takes this substep's step along the start-of-substep directions.
  bool start_directions(std::size_t t, double h);
  // Node i's step roots to leaves: dlambda and dx.
  template <int m>
  void substitute(std::size_t i);
  // The world impulse of node n's positional rows: the first three multipliers, or a slider's
  // lambda_1 t_1 + lambda_2 t_2 (kept in impulse).
  static Vec3d positional_impulse(const Node& n);
  // The tree's part of the merit's penalty at step length beta (bodies moved there).
  double merit_penalty(std::size_t begin, std::size_t end, std::span<const RigidBody> bodies, double beta) const;
  // Moves the tree's bodies by the first of beta = 1, 1/2, ... that decreases the merit enough.
  void line_search(std::size_t begin, std::size_t end, std::span<RigidBody> bodies);

  std::vector<TreeLink> links_;
  std::vector<char> in_forest_;
  std::vector<Node> nodes_;  // tree by tree; in a tree, parents before children
  std::vector<std::size_t> tree_start_;  // tree t is nodes [tree_start_[t], tree_start_[t + 1])
  std::vector<int> tree_of_body_;        // per body: its tree, or -1
  std::vector<char> end_directions_only_;  // per tree: an iterative joint acts on it
  std::vector<Work> work_;
};

}  // namespace seiche::rigid
