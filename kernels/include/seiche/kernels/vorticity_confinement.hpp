// Vorticity confinement (Fedkiw et al. 2001, as in Macklin & Müller 2013 eq. 15-16): puts back
// rotational energy that position-based damping removes.
//   omega_i = sum_j V_j (v_j - v_i) x grad_{p_j} W_ij           (V_j = m_j / rho_j)
//   eta_i   = sum_j V_j |omega_j| grad_{p_i} W_ij,   N = eta / |eta|   (0 where |eta| ~ 0)
//   v_i    += dt * epsilon * (N x omega_i)
// Two passes: vorticity, then the confinement velocity change.
#pragma once

#include <cstddef>

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

/// pos: (x, y, z, -); vel_volume: (vx, vy, vz, m/rho). Writes omega of particles [0, n).
void compute_vorticity(const Float4* pos, const Float4* vel_volume, NeighborSpan nbr,
                       std::size_t n, float h, float* omega_x, float* omega_y, float* omega_z);

/// pos_volume: (x, y, z, m/rho); omega_norm[j] = |omega_j|. Adds dt eps (N x omega) to v.
void apply_vorticity_confinement(const Float4* pos_volume, const float* omega_norm,
                                 const float* omega_x, const float* omega_y, const float* omega_z,
                                 NeighborSpan nbr, std::size_t n, float h, float epsilon, float dt,
                                 float* vx, float* vy, float* vz);

}  // namespace seiche::kernels
