#include "seiche/kernels/vorticity_confinement.hpp"

#include <cmath>

#include <tbb/parallel_for.h>

#include "seiche/kernels/sph_kernels.hpp"

namespace seiche::kernels {

// Scalar loops: vorticity confinement is an optional, cheaper pass than the density solve.
// grad_{p_i} W_ij = g (x_i - x_j) with g = spiky_grad_over_r; grad_{p_j} W_ij = -that.

void compute_vorticity(const Float4* pos, const Float4* vel_volume, NeighborSpan nbr,
                       std::size_t n, float h, float* omega_x, float* omega_y, float* omega_z) {
  const SphKernel kernel(h);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const Float4 pi = pos[i], vi = vel_volume[i];
      float wx = 0, wy = 0, wz = 0;
      for (std::uint32_t k = nbr.offsets[i]; k < nbr.offsets[i + 1]; ++k) {
        const std::uint32_t j = nbr.indices[k];
        const Float4 pj = pos[j], vj = vel_volume[j];
        const float dx = pi.x - pj.x, dy = pi.y - pj.y, dz = pi.z - pj.z;
        const float g = -vj.w * kernel.spiky_grad_over_r(dx * dx + dy * dy + dz * dz);
        const float gx = g * dx, gy = g * dy, gz = g * dz;  // V_j grad_{p_j} W_ij
        const float ux = vj.x - vi.x, uy = vj.y - vi.y, uz = vj.z - vi.z;
        wx += uy * gz - uz * gy;
        wy += uz * gx - ux * gz;
        wz += ux * gy - uy * gx;
      }
      omega_x[i] = wx;
      omega_y[i] = wy;
      omega_z[i] = wz;
    }
  });
}

void apply_vorticity_confinement(const Float4* pos_volume, const float* omega_norm,
                                 const float* omega_x, const float* omega_y, const float* omega_z,
                                 NeighborSpan nbr, std::size_t n, float h, float epsilon, float dt,
                                 float* vx, float* vy, float* vz) {
  const SphKernel kernel(h);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const Float4 pi = pos_volume[i];
      float ex = 0, ey = 0, ez = 0;
      for (std::uint32_t k = nbr.offsets[i]; k < nbr.offsets[i + 1]; ++k) {
        const std::uint32_t j = nbr.indices[k];
        const Float4 pj = pos_volume[j];
        const float dx = pi.x - pj.x, dy = pi.y - pj.y, dz = pi.z - pj.z;
        const float g = pj.w * omega_norm[j] * kernel.spiky_grad_over_r(dx * dx + dy * dy + dz * dz);
        ex += g * dx;
        ey += g * dy;
        ez += g * dz;
      }
      const float len = std::sqrt(ex * ex + ey * ey + ez * ez);
      if (!(len > 1e-20f)) continue;  // no gradient of |omega|: no direction to confine toward
      const float nx = ex / len, ny = ey / len, nz = ez / len;
      const float s = dt * epsilon;
      vx[i] += s * (ny * omega_z[i] - nz * omega_y[i]);
      vy[i] += s * (nz * omega_x[i] - nx * omega_z[i]);
      vz[i] += s * (nx * omega_y[i] - ny * omega_x[i]);
    }
  });
}

}  // namespace seiche::kernels
