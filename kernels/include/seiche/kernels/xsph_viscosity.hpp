// XSPH artificial viscosity (Schechter & Bridson 2012, as in Macklin & Müller 2013 eq. 17),
// written as an SPH interpolation so that c is dimensionless:
//   v_i <- v_i + c sum_j (m_j / rho_j) (v_j - v_i) W(|x_i - x_j|)
// It pulls each particle's velocity toward its neighbors' average: coherent motion, less
// noise. Jacobi: all new velocities are computed from the old ones (read from `vel_volume`).
#pragma once

#include <cstddef>

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

/// pos: (x, y, z, -); vel_volume: (vx, vy, vz, m/rho) of every fluid particle [0, n).
/// Writes the new velocities to vx, vy, vz.
void xsph_viscosity(const Float4* pos, const Float4* vel_volume, NeighborSpan nbr, std::size_t n,
                    float h, float c, float* vx, float* vy, float* vz);

}  // namespace seiche::kernels
