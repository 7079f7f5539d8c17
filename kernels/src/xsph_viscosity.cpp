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
  const std::size_t groups = (n + kLanes - 1) / kLanes;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, 256 / kLanes), [&](const auto& range) {
    const Floats h2(kernel.h2), zero(0.0f);
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      const NeighborGroup group(nbr, g * kLanes, n);
      const Gathered4 pi = group.own(pos), vi = group.own(vel_volume);
      Floats ax(0.0f), ay(0.0f), az(0.0f);
      std::uint32_t k = 0;
      // Lane = particle: slot k holds the k-th neighbor of each of the group's particles.
      auto slot = [&](const auto& neighbor, auto masked, const Mask& valid) SEICHE_INLINE {
        const Gathered4 pj = gather4(pos, neighbor), vj = gather4(vel_volume, neighbor);
        const Floats dx = pi.x - pj.x, dy = pi.y - pj.y, dz = pi.z - pj.z;
        Floats s = xsimd::max(h2 - multiply_add(dz, dz, multiply_add(dy, dy, dx * dx)), zero);
        if constexpr (decltype(masked)::value) s = xsimd::select(valid, s, zero);
        const Floats weight = vj.w * (s * s * s);
        ax = multiply_add(weight, vj.x - vi.x, ax);
        ay = multiply_add(weight, vj.y - vi.y, ay);
        az = multiply_add(weight, vj.z - vi.z, az);
      };
      const Mask all(true);
      for (; k < group.kmin; ++k)
        slot([&](std::size_t l) { return group.neighbor(l, k); }, std::false_type{}, all);
      for (; k < group.kmax; ++k)
        slot([&](std::size_t l) { return group.neighbor_clamped(l, k); }, std::true_type{},
             Floats(float(k)) < group.count);
      group.store(vx, vi.x + Floats(scale) * ax);
      group.store(vy, vi.y + Floats(scale) * ay);
      group.store(vz, vi.z + Floats(scale) * az);
    }
  });
}

}  // namespace seiche::kernels
