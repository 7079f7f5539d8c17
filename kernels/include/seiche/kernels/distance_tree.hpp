// Exact XPBD projection of a forest of distance constraints in linear time (the sparse
// elimination of Baraff 1996, "Linear-time dynamics using Lagrange multipliers"; as a PBD solve,
// Deul et al. 2018, "Direct position-based solver for stiff rods").
//
// One XPBD iteration on a set of constraints C_e solves the linearized system
//   K dx = sum_e grad C_e^T dlambda_e                                    (every particle)
//   grad C_e . dx + alpha~_e dlambda_e = -C_e - alpha~_e lambda_e =: b_e  (every constraint)
// with K = M. Gauss-Seidel solves it one constraint at a time, so a load moves about one edge
// per color and a point pin under a whole sheet is never reached. When the constraints form a
// forest, the system (particles and constraints as the nodes of one graph) is a forest too, and
// eliminating it from the leaves to the roots creates no fill-in. Vertex v has one parent edge e
// to its parent p, n = (x_v - x_p) / |x_v - x_p| (grad_v C_e = n, grad_p C_e = -n); leaves first:
//   K_v += sum_{children c} n_c n_c^T / d_c,   r_v = -sum_c n_c s_c      (3 x 3, SPD)
//   u = K_v^-1 n,   d_e = n . u + alpha~_e,   s_e = (b_e - u . r_v) / d_e
// then from the roots down (a root is fixed if pinned, w = 0, else dx_root = K^-1 r):
//   dlambda_e = s_e + n . dx_p / d_e,   dx_v = K_v^-1 (n dlambda_e + r_v),   lambda_e += dlambda_e.
// For one edge to a pin this is the XPBD step dx = w n dlambda, dlambda = b / (w + alpha~).
//
// Geometric stiffness. The linearization has no first-order stiffness across an edge, so a
// load across a taut chain (a flat sheet under gravity) would swing it far in one step. As in
// Andrews, Teichmann and Kry 2017 ("Geometric stiffness for real-time constrained multibody
// dynamics"), K gets the diagonal blocks of the geometric stiffness of each forest edge,
//   K_v = M_v I + G_v,   G_v = sum_{edges e at v} k_e (I - n_e n_e^T),
//   k_e = min(T_e / l_e, gamma min(M_i, M_j)),   T_e = max(0, -tension_e),
// where tension_e is the edge's multiplier of the previous substep (XPBD units, force dt^2).
//
// Safeguards (the step must not make things worse; issue 3):
// 1. Metric. With K != M the step is a projection in the metric K, not M: the lumped G acts as
//    extra transverse mass in the solve that the velocity update does not see, and at large
//    substeps that turns into energy (+13 % in 10 frames at one substep and iteration per
//    1/24 s, 16 x 16 sheet). The cap gamma = 4 (k_e at most gamma times the lighter free end's
//    mass) bounds the distortion, M_v <= K_v <= (1 + gamma deg_v) M_v. It binds where
//    T_e / (l_e M) > gamma, i.e. where the tension alone would move the lighter end sideways by
//    more than gamma edge lengths within the substep: there a linearized rotation means little.
// 2. Line search. The step (dx, dlambda) of each tree is scaled by the first beta of
//    1, 1/2, ..., 1/16 that decreases the l1 merit of the tree's part of the substep's problem
//      phi(beta) = beta^2/2 (sum_v M_v |dx_v|^2 + sum_e alpha~_e dlambda_e^2)
//                  + sum_e |dlambda_e| |C_e(x + beta dx) + alpha~_e (lambda_e + beta dlambda_e)|
//    enough (Armijo: phi(beta) <= phi(0) + 0.1 beta phi'(0), phi(0) = -phi'(0) = sum |dlambda||b|:
//    the step zeroes the linearized residual, and the inertia term has slope 0 at x). For linear
//    constraints beta = 1 passes (M dx . dx <= sum |dlambda||b|); where the linearization is
//    invalid (an edge turned far within one step, whose length then grows as its transverse
//    move squared) the step is shortened; a tree along which no step decreases phi is left as
//    it is. Deterministic: one tree, one serial loop, sums in position order.
// This changes the path of the Newton step, not its fixed point: the multipliers are the
// constraints' own (shared with the colored solve), so C + alpha~ lambda = 0, and with it the
// compliance, does not depend on the solve order or the number of iterations.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "seiche/kernels/distance_constraint.hpp"
#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

/// A forest over particles, tree by tree; inside a tree a vertex comes after its parent, and
/// the tree's root comes first.
struct DistanceForest {
  static constexpr std::uint32_t kRoot = ~0u;
  std::vector<std::uint32_t> particle;    ///< store index of the vertex at each position
  std::vector<std::uint32_t> parent;      ///< position of the parent (< own position), or kRoot
  std::vector<std::uint32_t> edge;        ///< index of the parent edge in the DistanceConstraints
  std::vector<std::uint32_t> tree_start;  ///< tree t is positions [tree_start[t], tree_start[t+1])
  std::vector<float> scratch;             ///< 16 floats per position, reused by every solve

  std::size_t size() const { return particle.size(); }
  std::size_t trees() const { return tree_start.empty() ? 0 : tree_start.size() - 1; }
  void remap(std::span<const std::uint32_t> new_index);
};

/// Builds a forest from parent links given in an order where every parent comes before its
/// children (parent = kRoot for a root; edge ignored there): regroups it tree by tree, keeping
/// that order inside each tree, and drops the trees of fewer than min_vertices vertices (at
/// least the roots without children).
DistanceForest make_distance_forest(std::span<const std::uint32_t> particle,
                                    std::span<const std::uint32_t> parent,
                                    std::span<const std::uint32_t> edge, std::size_t min_vertices = 2);

/// The cap gamma of the geometric stiffness (above): at most this many times the lighter end's mass.
inline constexpr float kGeometricStiffnessCap = 4.0f;

/// One exact, linearized XPBD projection of the forest's edges (one iteration), with their
/// rest lengths, compliances and multipliers from `c`; tension[k] (nullable) is constraint k's
/// multiplier of the previous substep, for the geometric stiffness. Each tree's step is
/// line-searched (safeguard 2). Trees run in parallel, each serially: the result does not depend
/// on the thread count.
void solve_distance_forest(const ParticleView& p, DistanceConstraints& c, DistanceForest& f, float dt,
                           const float* tension);

}  // namespace seiche::kernels
