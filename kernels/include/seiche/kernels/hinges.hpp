// Hinges: the bending elements of a triangle mesh. Hinge k is an interior edge (a, b) with its
// two wing vertices c (triangle a, b, c) and d (triangle b, a, d), both triangles oriented
// alike. The signed dihedral angle theta of a hinge is the angle between the triangles'
// normals n1 = (b - a) x (c - a) and n2 = (a - b) x (d - b):
//   theta = atan2((n1 x n2) . e, n1 . n2) with e = (b - a) / |b - a|;  flat: theta = 0.
// Both bending models (dihedral_bending.hpp, isometric_bending.hpp) store their hinges color by
// color here, and the run report's bending error is measured on them the same way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

struct Hinges {
  std::vector<std::uint32_t> a, b, c, d;  ///< store indices (remapped on reorder)
  std::vector<float> rest_angle;          ///< rad, theta of the rest shape, in (-pi, pi]
  std::vector<float> compliance;          ///< per hinge, as the solve uses it (see each model)
  std::vector<float> lambda;              ///< XPBD multiplier, from 0 every substep (a reset,
                                          ///< or the first solve with Multipliers::Restart)
  std::vector<std::uint32_t> color_start; ///< color c: hinges [color_start[c], color_start[c+1])

  std::size_t size() const { return a.size(); }
  std::size_t colors() const { return color_start.empty() ? 0 : color_start.size() - 1; }
  void remap(std::span<const std::uint32_t> new_index);
};

/// A hinge is degenerate (it has no angle and no gradient) when its edge is shorter than
/// 1e-9 m, |b - a|^2 <= kHingeMinEdge2, or a wing is flat, |n|^2 <= kHingeMinWing * |b - a|^4
/// (the wing's height over the edge below 1e-6 |b - a|: below float resolution).
inline constexpr float kHingeMinEdge2 = 1e-18f;  ///< m^2
inline constexpr float kHingeMinWing = 1e-12f;

/// Signed dihedral angle (rad) of a hinge at the given positions; 0 for a degenerate hinge
/// (zero-length edge or zero-area wing).
float dihedral_angle(const float pa[3], const float pb[3], const float pc[3], const float pd[3]);
/// The same in double precision (rest shapes, error metrics, reference checks).
double dihedral_angle(const double pa[3], const double pb[3], const double pc[3],
                      const double pd[3]);

/// What both bending models share: colors the hinges (hinge_vertices: a, b, c, d per hinge,
/// graph_coloring.hpp), stores them color by color with their rest angle (from the positions
/// x, y, z of `rest`, in double; 0 for a degenerate rest hinge) and lambda = 0, and sizes
/// `compliance` (left for the model to fill). Returns the input index of each stored hinge.
std::vector<std::uint32_t> build_hinges(std::span<const std::uint32_t> hinge_vertices,
                                        const ParticleView& rest, Hinges& out);

/// |theta - rest_angle| (rad), wrapped into [0, pi], over all hinges at positions x, y, z.
struct BendingError {
  double mean = 0.0, max = 0.0;
};
BendingError bending_error(const ParticleView& p, const Hinges& h);

}  // namespace seiche::kernels
