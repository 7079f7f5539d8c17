// XPBD distance constraint (Müller et al. 2007; compliance after Macklin et al. 2016):
//   C(p_i, p_j) = |p_i - p_j| - d,        n = (p_i - p_j) / |p_i - p_j|
//   alpha~ = compliance / dt^2
//   dlambda = (-C - alpha~ lambda) / (w_i + w_j + alpha~),   lambda += dlambda
//   p_i += w_i dlambda n,    p_j -= w_j dlambda n
// With compliance 0 and one iteration this is the PBD projection of the seed slides: it moves
// p_i and p_j along n in the ratio of their inverse masses until |p_i - p_j| = d.
// Coincident particles (|p_i - p_j| ~ 0) have no direction n: the constraint is skipped that
// iteration rather than producing NaN.
//
// Constraints are solved color by color (Gauss-Seidel between colors); no two constraints of
// one color share a particle, so a color runs in parallel with a result that does not depend
// on the thread count.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "seiche/kernels/packed_positions.hpp"
#include "seiche/kernels/particle_view.hpp"
#include "seiche/kernels/xpbd_multipliers.hpp"

namespace seiche::kernels {

/// A set of distance constraints stored color by color: color c is [color_start[c],
/// color_start[c+1]).
struct DistanceConstraints {
  std::vector<std::uint32_t> i, j;
  std::vector<float> rest_length;  ///< m
  std::vector<float> compliance;   ///< m/N
  std::vector<float> lambda;       ///< accumulated multiplier, from 0 every substep (a reset, or
                                   ///< the substep's first solve with Multipliers::Restart)
  std::vector<std::uint32_t> color_start;

  std::size_t size() const { return i.size(); }
};

/// Greedy coloring: builds `out` from unordered pairs, constraints of one color kept in input
/// order. Returns for each output constraint its input index.
std::vector<std::uint32_t> color_distance_constraints(std::span<const std::uint32_t> i,
                                                      std::span<const std::uint32_t> j,
                                                      std::span<const float> rest_length,
                                                      std::span<const float> compliance,
                                                      std::size_t particle_count,
                                                      DistanceConstraints& out);

/// One XPBD iteration over every constraint (all colors), on positions packed by the caller
/// (their range must cover every index of c).
void solve_distance_constraints(const PackedPositions& packed, DistanceConstraints& c, float dt,
                                Multipliers start);
/// The same on the store's columns (packs and unpacks the constraints' range), accumulating lambda.
void solve_distance_constraints(const ParticleView& p, DistanceConstraints& c, float dt);

/// The strain of one constraint (or mesh edge) (a, b) of rest length d at positions x, y, z:
///   |C| / d,  C = |x_a - x_b| - d  (in double; |C| in metres where d = 0).
/// The error metrics of the distance constraints and of the cloth's edges both use it.
inline double edge_strain(const ParticleView& p, std::uint32_t a, std::uint32_t b,
                          float rest_length) {
  const double dx = double(p.x[a]) - p.x[b], dy = double(p.y[a]) - p.y[b],
               dz = double(p.z[a]) - p.z[b];
  const double rest = rest_length;
  const double c = std::abs(std::sqrt(dx * dx + dy * dy + dz * dz) - rest);
  return rest > 0.0 ? c / rest : c;
}

/// edge_strain per constraint (mean and max), evaluated at positions x, y, z.
struct DistanceError {
  double mean = 0.0, max = 0.0;
};
DistanceError distance_constraint_error(const ParticleView& p, const DistanceConstraints& c);

}  // namespace seiche::kernels
