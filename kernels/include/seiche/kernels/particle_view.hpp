// What kernels see of the particle store: raw SoA pointers and a count. Kernels own nothing,
// do no I/O and keep no state between calls.
#pragma once

#include <cstddef>
#include <cstdint>

namespace seiche::kernels {

struct ParticleView {
  std::size_t n = 0;
  float *x = nullptr, *y = nullptr, *z = nullptr;     // positions at substep start
  float *px = nullptr, *py = nullptr, *pz = nullptr;  // predicted positions
  float *vx = nullptr, *vy = nullptr, *vz = nullptr;  // velocities
  const float* w = nullptr;                           // inverse masses (0 = pinned)
  const float* radius = nullptr;                      // collision radii (m)
};

/// A neighbor list in CSR form: neighbors of i are indices[offsets[i] .. offsets[i+1]).
struct NeighborSpan {
  const std::uint32_t* offsets = nullptr;
  const std::uint32_t* indices = nullptr;
};

/// Four floats in one 16-byte load: what neighbor passes gather per neighbor (x, y, z and one
/// per-particle value), the layout GPU engines use for positions.
struct alignas(16) Float4 {
  float x, y, z, w;
};

}  // namespace seiche::kernels
