#include "seiche/kernels/integrate.hpp"

#include <tbb/parallel_for.h>

namespace seiche::kernels {

namespace {
constexpr std::size_t kGrain = 8192;
}

// Plain loops over contiguous SoA arrays that the compiler vectorizes (lane = particle): the
// restrict-qualified locals tell it the columns do not overlap, and the scalars are captured by
// value so that no store can alias them.
void predict_positions(const ParticleView& p, float dt, const float gravity[3]) {
  const float gx = dt * gravity[0], gy = dt * gravity[1], gz = dt * gravity[2];
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.n, kGrain), [=, &p](const auto& r) {
    const float* __restrict x = p.x;
    const float* __restrict y = p.y;
    const float* __restrict z = p.z;
    const float* __restrict w = p.w;
    float* __restrict vx = p.vx;
    float* __restrict vy = p.vy;
    float* __restrict vz = p.vz;
    float* __restrict px = p.px;
    float* __restrict py = p.py;
    float* __restrict pz = p.pz;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const float free = w[i] > 0.0f ? 1.0f : 0.0f;
      const float ux = vx[i] + free * gx, uy = vy[i] + free * gy, uz = vz[i] + free * gz;
      vx[i] = ux, vy[i] = uy, vz[i] = uz;
      px[i] = x[i] + dt * ux;
      py[i] = y[i] + dt * uy;
      pz[i] = z[i] + dt * uz;
    }
  });
}

void update_velocities(const ParticleView& p, float dt) {
  const float inv_dt = 1.0f / dt;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.n, kGrain), [=, &p](const auto& r) {
    float* __restrict x = p.x;
    float* __restrict y = p.y;
    float* __restrict z = p.z;
    float* __restrict vx = p.vx;
    float* __restrict vy = p.vy;
    float* __restrict vz = p.vz;
    const float* __restrict px = p.px;
    const float* __restrict py = p.py;
    const float* __restrict pz = p.pz;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      vx[i] = (px[i] - x[i]) * inv_dt;
      vy[i] = (py[i] - y[i]) * inv_dt;
      vz[i] = (pz[i] - z[i]) * inv_dt;
      x[i] = px[i];
      y[i] = py[i];
      z[i] = pz[i];
    }
  });
}

void damp_velocities(const ParticleView& p, float factor) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.n, kGrain), [=, &p](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      if (p.w[i] <= 0.0f) continue;  // a kinematic particle keeps its velocity
      p.vx[i] *= factor;
      p.vy[i] *= factor;
      p.vz[i] *= factor;
    }
  });
}

}  // namespace seiche::kernels
