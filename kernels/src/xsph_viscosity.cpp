#include "seiche/kernels/xsph_viscosity.hpp"

#include <tbb/parallel_for.h>

#include "seiche/kernels/sph_kernels.hpp"
#include "simd.hpp"

namespace seiche::kernels {

using namespace simd;

void xsph_viscosity(const Float4* pos, const Float4* vel_volume, NeighborSpan nbr, std::size_t n,
                    float h, float c, float* vx, float* vy, float* vz) {
  const SphKernel kernel(h);
  const float scale = c * kernel.poly6_coeff;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
    const Floats lanes = lane_index();
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const std::uint32_t begin = nbr.offsets[i], count = nbr.offsets[i + 1] - begin;
      const std::uint32_t* list = nbr.indices + begin;
      const Floats xi(pos[i].x), yi(pos[i].y), zi(pos[i].z);
      const Float4 vi = vel_volume[i];
      Floats ax(0.0f), ay(0.0f), az(0.0f);
      for (std::size_t k = 0; k < count; k += kLanes) {
        const Mask valid = lanes < Floats(float(count - k));
        const Ints index = load_indices(list, count, k, std::int32_t(i));
        const Gathered4 pj = gather4(pos, index);
        const Gathered4 vj = gather4(vel_volume, index);
        const Floats dx = xi - pj.x, dy = yi - pj.y, dz = zi - pj.z;
        const Floats s = xsimd::max(Floats(kernel.h2) - (dx * dx + dy * dy + dz * dz), Floats(0.0f));
        const Floats weight = xsimd::select(valid, vj.w * s * s * s, Floats(0.0f));
        ax += weight * (vj.x - Floats(vi.x));
        ay += weight * (vj.y - Floats(vi.y));
        az += weight * (vj.z - Floats(vi.z));
      }
      vx[i] = vi.x + scale * xsimd::hadd(ax);
      vy[i] = vi.y + scale * xsimd::hadd(ay);
      vz[i] = vi.z + scale * xsimd::hadd(az);
    }
  });
}

}  // namespace seiche::kernels
