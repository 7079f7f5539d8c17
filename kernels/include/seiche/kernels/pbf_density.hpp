// Position Based Fluids density constraint (Macklin & Müller 2013), one Jacobi iteration in two
// passes over the fluid particles (sorted by cell; neighbors from a CSR list, self excluded).
//
// With V = m / rho0 the rest volume of a particle and W, grad W the kernels of sph_kernels.hpp:
//   density      rho_i = m (W(0) + sum_j W(|p_i - p_j|)) + rho0 f_walls(p_i)
//                (f_walls, its gradient and its push in dp_i: see pbf_walls.hpp)
//                + rho_b,i where a boundary is given (rigid bodies' boundary particles, from
//                core/src/families/fluid_body/: their density at p_i and their part g_b,i of
//                grad_{p_i} C_i, which joins the gradient sum of the denominator; their part of
//                dp_i, lambda_i g_b,i, is the caller's, with the reaction on the bodies)
//   constraint   C_i = max(rho_i / rho0 - 1, 0)           (unilateral: no pull at free surfaces)
//   gradients    grad_{p_i} C_i = V sum_j grad W_ij,       grad_{p_j} C_i = -V grad W_ij
//   lambda       lambda_i = -C_i / (sum_k |grad_{p_k} C_i|^2 + eps)
//   correction   dp_i = V sum_j (lambda_i + lambda_j + s_corr_ij) grad W_ij
//   s_corr_ij = -k max(u^n - u_s^n, 0) / (1 - u_s^n) / D0     (artificial pressure, eq. 13,
//                u = W(|p_i - p_j|) / W(dq h), u_s = W(s) / W(dq h) at the rest spacing s)
// eps (constraint force mixing) softens the constraint and keeps the division finite where a
// particle has no neighbor. D0 is the lambda denominator of a particle in a full rest lattice:
// dividing by it makes s_corr a multiplier like lambda (m^2 here), so k reads as "the
// compression this repulsion is worth at r = dq h" and does not depend on the resolution. The
// paper's term, -k u^n, still pushes at the rest spacing: at a free surface, where the
// unilateral constraint has nothing to push back, it acts as a gas pressure that lifts the fluid
// (a 6^3 block at spacing 0.05 m gained 21 % energy). Shifted by its value at s, it is 0 for
// r >= s, so it only pushes apart pairs closer than the rest spacing (the clumping it is there
// to prevent), never beyond it; rescaled by 1 / (1 - u_s^n), it is still exactly k at r = dq h.
// Where dq h >= s (u_s >= 1) there is no artificial pressure.
//
// Pass 1 reads packed positions (x, y, z, -) and writes density and lambda; pass 2 reads packed
// positions with lambda in w and adds dp_i to the predicted positions px, py, pz (which are not
// read by either pass, so the iteration is a true Jacobi step). Vectorized across particles
// (lane = particle: a batch holds consecutive particles and step k visits the k-th neighbor of
// each, records gathered with 16-byte loads), parallel across batches; every particle's sums
// run in neighbor-list order in its own lane, so results do not depend on the thread count.
#pragma once

#include <cstddef>

#include "seiche/kernels/particle_view.hpp"
#include "seiche/kernels/sph_kernels.hpp"

namespace seiche::kernels {

struct PbfParams {
  float h = 0.04f;           ///< kernel radius (m)
  float mass = 0.008f;       ///< particle mass (kg)
  float rest_density = 1000.0f;
  float epsilon = 0.0f;      ///< absolute constraint force mixing term (1/m^2)
  float lambda_scale = 1.0f; ///< 1 / D0 (m^2): the unit of s_corr
  float tensile_k = 0.0f;    ///< 0 = no artificial pressure
  int tensile_n = 4;          ///< 1..8
  /// Axis-aligned walls (the domain box) that lend density to particles within h of them
  /// (pbf_walls.hpp); off: particles at walls see only their fluid neighbors.
  bool walls = false;
  float wall_min[3] = {0, 0, 0};
  float wall_max[3] = {0, 0, 0};
  /// Scales the continuous wall share so that a rest lattice half a spacing from a wall is at
  /// rest density: lattice_wall_share / wall_density_fraction(spacing / 2, h).
  float wall_scale = 1.0f;
  float tensile_dq = 0.2f;   ///< fraction of h
  /// The rest spacing s (m), from which on s_corr is 0 (0: the paper's unshifted term).
  float tensile_rest_distance = 0.0f;
  /// Per particle (g_b.x, g_b.y, g_b.z, rho_b) of the boundary particles near it, or null (no
  /// boundary: pass 1 reads nothing more). Read by pass 1 only.
  const Float4* boundary = nullptr;
};

/// The sum over an ideal lattice of spacing s of W(|k s|) (self included), for the particle mass
/// that makes a lattice exactly rest density: mass = rest_density / lattice_kernel_sum.
double lattice_kernel_sum(float spacing, float h);
/// The lambda denominator sum_k |grad C|^2 of a particle inside that lattice (with V = m/rho0):
/// the scale against which the relaxation epsilon is given.
double lattice_lambda_denominator(float spacing, float h);
/// The share of that lattice sum lying behind a wall for a particle half a spacing in front of
/// it: what the wall must lend for the lattice at the wall to read rest density.
double lattice_wall_share(float spacing, float h);

/// Pass 1 over particles [0, n): density[i], lambda[i].
void pbf_density_lambda(const Float4* pos, NeighborSpan nbr, std::size_t n, const PbfParams& prm,
                        float* density, float* lambda);
/// Pass 2 over particles [0, n): px/py/pz[i] += dp_i. pos_lambda holds (x, y, z, lambda).
void pbf_apply_correction(const Float4* pos_lambda, NeighborSpan nbr, std::size_t n,
                          const PbfParams& prm, float* px, float* py, float* pz);

/// Scalar references of both passes (the oracle of the vectorized ones; tests only).
void pbf_density_lambda_reference(const Float4* pos, NeighborSpan nbr, std::size_t n,
                                  const PbfParams& prm, float* density, float* lambda);
void pbf_apply_correction_reference(const Float4* pos_lambda, NeighborSpan nbr, std::size_t n,
                                    const PbfParams& prm, float* px, float* py, float* pz);

}  // namespace seiche::kernels
