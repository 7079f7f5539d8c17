#include "seiche/kernels/integrate.hpp"

#include <tbb/parallel_for.h>

namespace seiche::kernels {

namespace {
constexpr std::size_t kGrain = 4096;
}

// Plain loops over contiguous SoA arrays: the compiler vectorizes them (lane = particle).
void predict_positions(const ParticleView& p, float dt, const float gravity[3]) {
  const float gx = dt * gravity[0], gy = dt * gravity[1], gz = dt * gravity[2];
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.n, kGrain), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const float free = p.w[i] > 0.0f ? 1.0f : 0.0f;
      p.vx[i] += free * gx;
      p.vy[i] += free * gy;
      p.vz[i] += free * gz;
      p.px[i] = p.x[i] + dt * p.vx[i];
      p.py[i] = p.y[i] + dt * p.vy[i];
      p.pz[i] = p.z[i] + dt * p.vz[i];
    }
  });
}

void update_velocities(const ParticleView& p, float dt) {
  const float inv_dt = 1.0f / dt;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.n, kGrain), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      p.vx[i] = (p.px[i] - p.x[i]) * inv_dt;
      p.vy[i] = (p.py[i] - p.y[i]) * inv_dt;
      p.vz[i] = (p.pz[i] - p.z[i]) * inv_dt;
      p.x[i] = p.px[i];
      p.y[i] = p.py[i];
      p.z[i] = p.pz[i];
    }
  });
}

}  // namespace seiche::kernels
