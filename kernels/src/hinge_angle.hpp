// The signed dihedral angle of a hinge (a, b, c, d) (hinges.hpp), written once for every number
// type that computes it (internal to kernels/): double for rest angles, double batches for the
// bending error, float batches for the dihedral bending solve.
//   e = b - a,  n1 = e x (c - a),  n2 = (d - b) x e  (= (a - b) x (d - b)),
//   theta = atan2((n1 x n2) . e / |e|, n1 . n2);
// the hinge has no angle (degenerate) where |e|^2 <= kHingeMinEdge2 or a wing is flat,
// |n_i|^2 <= kHingeMinWing |e|^4. The caller picks the atan2 (the C library's, simd::atan2 or
// xsimd's) and the edge length to divide by (a solve divides by 1 in degenerate lanes to keep
// them finite); the operations and their order are the same for every type.
#pragma once

#include <utility>

#include "colored_batches.hpp"
#include "seiche/kernels/hinges.hpp"

namespace seiche::kernels {

/// A hinge's edge, wing normals and their squared lengths, at p[0..3] = a, b, c, d. (Built in
/// place by its constructor: a frame returned by value was copied through the stack, which made
/// the bending error's double batches twice as slow.)
template <class T>
struct HingeFrame {
  colored::V3<T> e, n1, n2;
  T e2, n1sq, n2sq;

  SEICHE_INLINE explicit HingeFrame(const colored::V3<T> p[4])
      : e(p[1] - p[0]),
        n1(cross(e, p[2] - p[0])),
        n2(cross(p[3] - p[1], e)),
        e2(dot(e, e)),
        n1sq(dot(n1, n1)),
        n2sq(dot(n2, n2)) {}
};

/// Where the hinge has an angle (bool for a scalar T, a lane mask for a batch).
template <class T>
SEICHE_INLINE inline auto has_angle(const HingeFrame<T>& h) {
  using Mask = decltype(std::declval<T>() > std::declval<T>());
  const T min_wing = T(kHingeMinWing) * h.e2 * h.e2;
  return Mask((h.e2 > T(kHingeMinEdge2)) & (h.n1sq > min_wing) & (h.n2sq > min_wing));
}

/// theta (rad, in (-pi, pi]) of a hinge that has an angle; edge_length is |e| = sqrt(h.e2).
template <class T, class Atan2>
SEICHE_INLINE inline T hinge_angle(const HingeFrame<T>& h, const T& edge_length, Atan2&& atan2) {
  return atan2(dot(cross(h.n1, h.n2), h.e) / edge_length, dot(h.n1, h.n2));
}

}  // namespace seiche::kernels
