// Dihedral-angle bending, XPBD (Müller et al. 2007, appendix; gradients after Bridson et al.
// 2003; the seed tutorial's bending constraint):
//   C = theta - theta0               (signed dihedral angle, hinges.hpp; wrapped into (-pi, pi])
//   dlambda = (-C - alpha~ lambda) / (sum_i w_i |grad_i C|^2 + alpha~),  alpha~ = alpha / dt^2
//   p_i += w_i grad_i C dlambda
// alpha per hinge is the cloth's bend compliance (1/(N m), the inverse of a bending stiffness
// k_b) scaled by the discrete-shells weight of the hinge, so that the energy
//   U = k_b * 3 |e|^2 / (A1 + A2) * (theta - theta0)^2 / 2
// matches the isometric model's for small angles and does not depend on the mesh resolution:
//   alpha_hinge = bend_compliance * (A1 + A2) / (3 |e|^2).
// Degenerate hinges (zero-length edge, zero-area wing) are skipped for the iteration.
#pragma once

#include <span>

#include "seiche/kernels/hinges.hpp"
#include "seiche/kernels/packed_positions.hpp"
#include "seiche/kernels/xpbd_multipliers.hpp"

namespace seiche::kernels {

/// Builds colored dihedral hinges. hinge_vertices: 4 per hinge (a, b, c, d); bend_compliance:
/// one per hinge (1/(N m)); the rest angle and the per-hinge scaling come from the positions
/// x, y, z of `rest` (a hinge with a degenerate rest shape gets rest angle 0 and compliance as
/// if |e|^2 = A1 + A2).
void build_dihedral_bending(std::span<const std::uint32_t> hinge_vertices,
                            std::span<const float> bend_compliance, const ParticleView& rest,
                            Hinges& out);

/// One XPBD iteration over every hinge, color by color, on positions packed by the caller (their
/// range must cover every index of the hinges).
void solve_dihedral_bending(const PackedPositions& packed, Hinges& h, float dt, Multipliers start);
/// The same on the store's columns (packs and unpacks the hinges' range), accumulating lambda.
void solve_dihedral_bending(const ParticleView& p, Hinges& h, float dt);

}  // namespace seiche::kernels
