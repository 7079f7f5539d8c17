// The exact solve of the ball joints along spanning trees of the bodies, per iteration: Baraff
// 1996 ("Linear-time dynamics using Lagrange multipliers") with 6 x 6 body blocks and 3-row
// joint blocks, as a position-level XPBD step (Deul et al. 2018). A chain of 1:1000 mass ratio
// hangs as stiffly as one of equal links, where one Gauss-Seidel sweep moves a load about one
// joint and lets the heavy end stretch the chain (the particles' version: kernels/
// distance_tree.hpp).
//
// One iteration solves the linearization at the current positions, for all ball joints e of
// the forest at once:
//   M_v dx_v = sum_{e at v} J_ev^T dlambda_e                          (every body v)
//   sum_v J_ev dx_v + alpha~_e dlambda_e = b_e := -C_e - alpha~_e lambda_e   (every joint e)
// dx_v = (dp, dtheta) the body's move and world rotation vector, M_v = diag(m I, I_world),
// C_e = P_b - P_a (P = x + r, r = R(q) anchor), alpha~ = compliance / h^2, lambda_e a 3-vector,
// J_eb = [I, -[r_b]x], J_ea = [-I, [r_a]x] (so M^-1 J^T p is the impulse p at P:
// x += p / m, dtheta = I^-1 (r x p), as body_correction.hpp).
// With the bodies and joints a forest, eliminating from the leaves to the roots makes no
// fill-in. Body v with parent joint e (its parent p: a body, or fixed) and child joints c
// (child body w), leaves first:
//   K_v = M_v + sum_c J_cv^T D_c^-1 J_cv,   r_v = sum_c J_cv^T s_c                  (6 x 6, SPD)
// (M_v plus the geometric stiffness below),
//   G = K_v^-1 J_ev^T,  u = K_v^-1 r_v,  D_e = J_ev G + alpha~_e I,  s_e = D_e^-1 (b_e - J_ev u)
// then from the roots down (a free root: dx = K^-1 r; a fixed parent: dx_p = 0):
//   dlambda_e = s_e - D_e^-1 J_ep dx_p,   dx_v = G dlambda_e + u,   lambda_e += dlambda_e,
// and last every body moves: x += dp, q += 1/2 [dtheta, 0] q, normalized (rotate_by_small).
// For one joint to the world it is the 3-row XPBD step dlambda = (J M^-1 J^T + alpha~)^-1 b.
//
// Geometric stiffness. The linearization has no first-order stiffness of a body's rotation at
// a loaded connector, so where a light body carries a large load (a 4 g link under a 4 kg end,
// T h^2 / (m l) about 1 at 8 substeps of 1/60 s) one step turns it far, and the chain gains
// energy and flies apart. As for the particles' forests (Andrews, Teichmann and Kry 2017), K_v
// gets the tension part of lambda . d^2 P / d theta^2 at each of its connectors,
//   K_v += k (I - r r^T / |r|^2)   on the rotation block,   k = max(f . r, 0),
// f the impulse of the joint on the body at lever r (+lambda on body_b, -lambda on body_a) at
// the end of the previous substep (these multipliers carry across substeps: the checkpoint holds
// them). Uncapped, unlike the particles' gamma: a cap at 4 times the body's smallest moment of
// inertia left the 1:1000 chain flying apart at 8 x 2; uncapped it holds (and gains no energy)
// from 1 substep of 1 iteration per 1/60 s up.
// Line search. The step (dx, dlambda) of each tree is scaled by the first beta of 1, 1/2, ...,
// 1/16 that decreases the particles' merit (distance_tree.hpp, safeguard 2) enough (Armijo 0.1),
//   phi(beta) = beta^2/2 (sum_v dx_v^T M_v dx_v + sum_e alpha~_e |dlambda_e|^2)
//               + sum_e |dlambda_e| |C_e(x + beta dx) + alpha~_e (lambda_e + beta dlambda_e)|;
// a tree along which no step decreases phi is left as it is.
//
// The forest: the graph of the movable bodies and one ground node (the world and every fixed
// body), over the ball joints in scene order; a joint that closes a loop (through the ground
// too: a chain hung at both ends) is left out, and it and every other joint type keep the
// iterative solve (joint.hpp), which runs after this one. A tree per joint to the ground (the
// ground is fixed, so they are independent), then one per piece that does not reach it, rooted
// at its lowest-numbered body; inside a tree breadth first, children in scene order. Serial, one
// fixed order: the bits do not depend on the thread count.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "rigid_body.hpp"

namespace seiche::rigid {

/// A ball joint as the tree solve sees it (joint.hpp's Joint of type ball).
struct BallLink {
  int body_a = -1, body_b = -1;  ///< indices into the bodies; -1: the world
  Vec3d anchor_a, anchor_b;      ///< the connector point in each body's frame
  double compliance = 0.0;       ///< m/N
};

class JointTreeSolver {
 public:
  JointTreeSolver() = default;
  /// The forest over the `links` in their order, with `bodies` (which are fixed).
  JointTreeSolver(std::span<const BallLink> links, std::span<const RigidBody> bodies);

  bool empty() const { return nodes_.empty(); }
  /// Whether link k is in the forest (else the iterative solve keeps it).
  bool in_forest(std::size_t k) const { return in_forest_[k] != 0; }

  /// Before the first iteration of a substep: every multiplier to 0 (the last ones kept for the
  /// geometric stiffness).
  void reset_multipliers();
  /// The multipliers now, a node at a time (the checkpoint's state), and their restore.
  std::vector<Vec3d> multipliers() const;
  void restore_multipliers(std::span<const Vec3d> lambdas);
  /// One iteration: the exact step above over every tree.
  void solve(std::span<RigidBody> bodies, double h);

 private:
  using Mat6 = std::array<double, 36>;  // row-major
  using Vec6 = std::array<double, 6>;
  struct Node {
    int body = 0;
    int parent = -1;        ///< position of the parent body's node; -1: a root (fixed parent or free)
    int link = -1;          ///< the parent joint (into links_); -1: a free root
    bool body_is_b = true;  ///< the body is the link's body_b
    Vec3d lambda;           ///< the parent joint's multiplier (N s^2), within a substep
    Vec3d previous_lambda;  ///< its value at the end of the previous substep
  };
  // Per node, rebuilt every solve.
  struct Work {
    Mat6 k;                       // K_v, then its Cholesky factor
    Vec6 r, u, dx;
    std::array<double, 18> g;     // G = K_v^-1 J_ev^T (6 x 3)
    std::array<double, 18> jp;    // J_ep (3 x 6); unused for a fixed parent
    std::array<double, 9> d_inv;  // D_e^-1
    Vec3d s;
    Vec3d b, dlambda;  // b_e, and the step of lambda_e
    double alpha = 0.0;
    Vec3d x0;          // the body before the step (the line search)
    Quatd q0;
  };

  // The tree's part of the merit's penalty at step length beta (bodies moved there).
  double merit_penalty(std::size_t begin, std::size_t end, std::span<const RigidBody> bodies, double beta) const;
  // Moves the tree's bodies by the first of beta = 1, 1/2, ... that decreases the merit enough.
  void line_search(std::size_t begin, std::size_t end, std::span<RigidBody> bodies);

  std::vector<BallLink> links_;
  std::vector<char> in_forest_;
  std::vector<Node> nodes_;  // tree by tree; in a tree, parents before children
  std::vector<std::size_t> tree_start_;  // tree t is nodes [tree_start_[t], tree_start_[t + 1])
  std::vector<Work> work_;
};

}  // namespace seiche::rigid
