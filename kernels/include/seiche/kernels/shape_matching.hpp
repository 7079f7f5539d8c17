// Shape matching (Müller, Heidelberger, Teschner and Gross 2005, "Meshless deformations based on
// shape matching"; the seed tutorial's section 5.11): a cluster of particles keeps the shape it
// had at rest. With masses m_i, rest offsets q_i from the rest centre of mass and predicted
// positions p_i,
//   c = sum m_i p_i / sum m_i                        (the centre of mass now)
//   A = sum m_i (p_i - c) q_i^T                      (3 x 3)
//   R = the rotation closest to A                    (polar decomposition: A = R S)
//   g_i = c + R q_i                                  (the goal positions)
//   p_i += stiffness (g_i - p_i)                     (stiffness 1: rigid)
// Moving every particle to its goal keeps the centre of mass and the momentum (sum m_i (g_i -
// p_i) = 0 since sum m_i q_i = 0). R comes from the iterative method of Müller, Bender,
// Chentanez and Macklin 2016 ("A robust method to extract the rotational part of
// deformations"), warm-started from the cluster's rotation of the previous solve: it always
// returns a proper rotation, and where A says nothing (a flat, a linear or a one-particle
// cluster, or A = 0) it keeps the previous one, so it never divides by zero and never gives a
// NaN. The rotations are state: they are carried from solve to solve (and saved in checkpoints).
//
// Clusters must not share particles (each cluster is solved by one thread, in parallel); a
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

struct ShapeClusters {
  std::vector<std::uint32_t> start;     ///< cluster c owns members [start[c], start[c + 1])
  std::vector<std::uint32_t> particle;  ///< per member: its store index
  std::vector<float> stiffness;         ///< per cluster, in [0, 1]
  std::vector<Quaternion> rotation;     ///< per cluster: R of the last solve (state)

  std::size_t clusters() const { return stiffness.size(); }
  void remap(std::span<const std::uint32_t> new_index);
};

/// Rest offsets q_i of every particle from its cluster's rest centre of mass, one column per
/// axis, indexed by store index (the store moves them when it reorders).
struct RestOffsets {
  const float *x = nullptr, *y = nullptr, *z = nullptr;
};

/// One shape-matching projection of every cluster on the predicted positions.
void solve_shape_matching(const ParticleView& p, const RestOffsets& rest, ShapeClusters& clusters);

/// The rotation closest to `a` (row-major 3 x 3), starting from `guess`: what
/// solve_shape_matching does per cluster, for tests. Scale-free: a and k a give the same R.
Quaternion closest_rotation(const double a[9], Quaternion guess);

}  // namespace seiche::kernels
