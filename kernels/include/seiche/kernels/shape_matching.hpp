// Shape matching (Müller, Heidelberger, Teschner and Gross 2005, "Meshless deformations based on
// shape matching"; the seed tutorial's section 5.11): a cluster of particles keeps the shape it
// had at rest. With mass weights m_i, rest offsets q_i from the rest centre of mass and predicted
// positions p_i,
//   c   = sum m_i p_i / sum m_i                      (the centre of mass now)
//   Apq = sum m_i (p_i - c) q_i^T                    (3 x 3)
//   R   = the rotation closest to Apq                (polar decomposition: Apq = R S)
//   g_i = c + T q_i                                  (the goal positions)
//   p_i += stiffness (g_i - p_i)                     (stiffness 1: all the way)
// with T = R (rigid), or, with a linear blend beta in (0, 1] (Müller 2005, section 4.2),
//   A   = Apq Aqq,  Aqq = (sum m_i q_i q_i^T)^-1     (the best linear map from rest to now)
//   A  /= det(A)^(1/3)                               (volume kept)
//   T   = beta A + (1 - beta) R                      (beta 1: any linear deformation is a goal)
// The linear part is left out (T = R) where it is undefined: a flat, linear or coincident
// cluster (Aqq singular: det below 1e-9 of (trace / 3)^3), a crushed, inverted or torn one
// (det A outside (1/8, 8): rescaling it to its volume would throw the goals far out), non-finite.
// Moving every particle to its goal keeps the centre of mass and the momentum (sum m_i (g_i -
// p_i) = 0 since sum m_i q_i = 0). R comes from the iterative method of Müller, Bender,
// Chentanez and Macklin 2016 ("A robust method to extract the rotational part of
// deformations"), warm-started from the cluster's rotation of the previous solve: it always
// returns a proper rotation, and where A says nothing (a flat, a linear or a one-particle
// cluster, or A = 0) it keeps the previous one, so it never divides by zero and never gives a
// NaN. The rotations are state: they are carried from solve to solve (and saved in checkpoints).
//
// Plastic clusters (shape_plasticity.hpp) match a rest shape changed by a plastic deformation
// Sp (3 x 3, state): their rest offsets are Sp q_i.
//
// Overlapping clusters (region-based shape matching for large soft bodies, Müller 2005 section
// 4.5, Rivers and James 2007): a particle in N_i clusters weighs m_i / N_i in each (its `share`),
// every cluster computes its goals for its members, and each particle moves toward the average
// of its clusters' goals. With those weights the correction still keeps the momentum:
//   sum_i m_i (mean_k g_ik - p_i) = sum_k sum_{i in k} (m_i / N_i) (g_ik - p_i) = 0.
// Both halves (the clusters' goals, then the particles' averages) run in parallel, each sum in a
// fixed order on one thread: the result does not depend on the thread count.
//
// Clusters that do not overlap move their members directly (the common case, one per body); a
// pinned member (w = 0) weighs nothing and is not moved.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

/// A unit quaternion (x, y, z, w): the rotation of a cluster from its rest shape.
using Quaternion = std::array<float, 4>;
inline constexpr Quaternion kIdentityRotation = {0.0f, 0.0f, 0.0f, 1.0f};

/// A 3 x 3 matrix, row-major, in double.
using Matrix3 = std::array<double, 9>;
inline constexpr Matrix3 kIdentityMatrix = {1, 0, 0, 0, 1, 0, 0, 0, 1};

/// Plastic flow of one cluster (Müller 2005, section 4.4); creep 0: elastic.
struct Plasticity {
  float yield = 0.0f;       ///< ||S - I||_F above which the rest shape flows
  float creep = 0.0f;       ///< 1/s: how fast the rest shape follows the deformation
  float max_strain = 1.0f;  ///< bound on ||Sp - I||_F
};

struct ShapeClusters {
  // Per cluster.
  std::vector<std::uint32_t> start;     ///< cluster c owns members [start[c], start[c + 1])
  std::vector<float> stiffness;         ///< in [0, 1]
  std::vector<float> linear_blend;      ///< beta in [0, 1]; 0: the rigid goal
  std::vector<std::uint8_t> overlapping;  ///< 1: its members are shared (goals are averaged)
  std::vector<Plasticity> plasticity;   ///< creep 0: elastic
  std::vector<Quaternion> rotation;     ///< R of the last solve (state)
  std::vector<Matrix3> plastic;         ///< Sp, the plastic deformation of its rest shape (state)

  // Per member.
  std::vector<std::uint32_t> particle;  ///< its store index
  std::vector<float> rest_x, rest_y, rest_z;  ///< q: offset from the cluster's rest centre of mass
  std::vector<float> share;             ///< overlapping clusters: 1 / N_i, the part of the mass it
                                        ///< carries (a member of another cluster weighs all of it)

  // Particles of overlapping clusters: each one's members, for the average of their goals.
  std::vector<std::uint32_t> shared_particle;  ///< store index
  std::vector<std::uint32_t> shared_start;     ///< shared particle j: [shared_start[j], shared_start[j + 1])
  std::vector<std::uint32_t> shared_member;    ///< member indices
  std::vector<float> shared_stiffness;         ///< per shared particle

  // Scratch: the goal of every member of an overlapping cluster.
  std::vector<double> goal_x, goal_y, goal_z;

  std::size_t clusters() const { return stiffness.size(); }
  std::size_t members() const { return particle.size(); }
  /// Appends a cluster with the default settings (rigid, elastic, not overlapping) and no
  /// members yet; add them with add_member, then close it with end_cluster.
  void begin_cluster(float cluster_stiffness);
  void add_member(std::uint32_t store_index, float qx, float qy, float qz, float mass_share = 1.0f);
  void end_cluster();
  /// Sizes the goal scratch (after the last cluster).
  void finish();
  void remap(std::span<const std::uint32_t> new_index);
};

/// One shape-matching projection of every cluster on the predicted positions.
void solve_shape_matching(const ParticleView& p, ShapeClusters& clusters);

/// The rotation closest to `a` (row-major 3 x 3), starting from `guess`: what
/// solve_shape_matching does per cluster, for tests. Scale-free: a and k a give the same R.
Quaternion closest_rotation(const double a[9], Quaternion guess);

}  // namespace seiche::kernels
