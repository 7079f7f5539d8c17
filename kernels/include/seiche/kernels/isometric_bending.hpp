// Isometric bending (Bergou et al. 2006, "A quadratic bending model for inextensible surfaces";
// the seed tutorial's second bending model), XPBD. For hinge (a, b, c, d) = (x0, x1, x2, x3):
//   e0 = x1 - x0, e1 = x2 - x0, e2 = x3 - x0, e3 = x2 - x1, e4 = x3 - x1   (rest positions)
//   K = (c03 + c04, c01 + c02, -c01 - c03, -c02 - c04),  cij = cot of the angle between ei, ej
//       (c03, c04 with -e0)
//   Q = 3 / (A1 + A2) K K^T  (4x4, symmetric);  energy U = k_b / 2 sum_ij Q_ij x_i . x_j
// U is zero for a flat hinge (the model assumes a flat rest shape) and exactly quadratic in
// the positions. As an XPBD constraint with U = C^2 / (2 alpha):
//   C = sqrt(sum_ij Q_ij x_i . x_j),  grad_i C = (sum_j Q_ij x_j) / C,  alpha = 1 / k_b
// (alpha is the cloth's bend compliance, 1/(N m), not scaled per hinge). Hinges with C below
// 1e-9 are flat and skipped for the iteration (their correction tends to zero there).
// Evaluated through the factor Q = k k^T, k = sqrt(3 / (A1 + A2)) K (exact: Q has rank 1):
//   v = sum_i k_i x_i,  C = |v|,  grad_i C = k_i v / |v|.
// Summing Q_ij x_i . x_j in float instead is ill-conditioned at a flat hinge: the rounding of
// the stored Q makes it indefinite by ~1e-7 |Q|, so C and grad C are both rounding noise there
// and the XPBD step C / |grad C|^2 grad C moves the vertices by about an edge length (a flat
// 16 x 16 sheet with 2 cm edges moved 8.7 mm in 10 stiff iterations that way).
#pragma once

#include <array>
#include <span>
#include <vector>

#include "seiche/kernels/hinges.hpp"
#include "seiche/kernels/packed_positions.hpp"
#include "seiche/kernels/xpbd_multipliers.hpp"

namespace seiche::kernels {

struct IsometricBending {
  Hinges hinges;
  /// The 10 distinct entries of each hinge's Q, one column per entry, in the order
  /// Q00 Q01 Q02 Q03 Q11 Q12 Q13 Q22 Q23 Q33 (1/m^2).
  std::array<std::vector<float>, 10> q;
  /// The factor of Q = k k^T per hinge, k_i = sqrt(3 / (A1 + A2)) K_i (1/m): what the solve
  /// uses (see above). k_0 = -(k_1 + k_2 + k_3).
  std::array<std::vector<float>, 4> k;

  std::size_t size() const { return hinges.size(); }
};

/// Builds colored isometric hinges; arguments as build_dihedral_bending (bend_compliance is
/// used as is). A degenerate rest hinge gets Q = 0 (no bending force).
void build_isometric_bending(std::span<const std::uint32_t> hinge_vertices,
                             std::span<const float> bend_compliance, const ParticleView& rest,
                             IsometricBending& out);

/// One XPBD iteration over every hinge, color by color, on positions packed by the caller (their
/// range must cover every index of the hinges).
void solve_isometric_bending(const PackedPositions& packed, IsometricBending& b, float dt,
                             Multipliers start);
/// The same on the store's columns (packs and unpacks the hinges' range), accumulating lambda.
void solve_isometric_bending(const ParticleView& p, IsometricBending& b, float dt);

}  // namespace seiche::kernels
