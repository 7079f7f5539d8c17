#include "seiche/kernels/integrate.hpp"

#include <algorithm>

#include "simd.hpp"

namespace seiche::kernels {

namespace {

using simd::Floats;
using simd::kLanes;
using simd::Lanes;
constexpr std::size_t kBatchesPerTask = 1024;  // 8,192 particles with 8 lanes

// The three passes, lane = particle, written with xsimd: as plain loops g++ left two of them
// scalar (it ignores __restrict on local pointers, gives up on run-time overlap checks for this
// many arrays, and keeps a branch for a float compare under -ftrapping-math). Each lane computes
// what the scalar formula does, in the same order: the same bits.
void predict_range(const ParticleView& p, std::size_t begin, std::size_t end, float dt,
                   const float g[3], const float g_pinned[3]) {
  for (std::size_t i = begin; i < end; i += kLanes) {
    const Lanes l{i, std::min(kLanes, end - i)};
    const simd::Mask free = l.load(p.w) > Floats(0.0f);
    const Floats ux = l.load(p.vx) + xsimd::select(free, Floats(g[0]), Floats(g_pinned[0]));
    const Floats uy = l.load(p.vy) + xsimd::select(free, Floats(g[1]), Floats(g_pinned[1]));
    const Floats uz = l.load(p.vz) + xsimd::select(free, Floats(g[2]), Floats(g_pinned[2]));
    l.store(p.vx, ux), l.store(p.vy, uy), l.store(p.vz, uz);
    l.store(p.px, l.load(p.x) + Floats(dt) * ux);
    l.store(p.py, l.load(p.y) + Floats(dt) * uy);
    l.store(p.pz, l.load(p.z) + Floats(dt) * uz);
  }
}

void update_range(const ParticleView& p, std::size_t begin, std::size_t end, float inv_dt) {
  for (std::size_t i = begin; i < end; i += kLanes) {
    const Lanes l{i, std::min(kLanes, end - i)};
    const Floats px = l.load(p.px), py = l.load(p.py), pz = l.load(p.pz);
    l.store(p.vx, (px - l.load(p.x)) * Floats(inv_dt));
    l.store(p.vy, (py - l.load(p.y)) * Floats(inv_dt));
    l.store(p.vz, (pz - l.load(p.z)) * Floats(inv_dt));
    l.store(p.x, px), l.store(p.y, py), l.store(p.z, pz);
  }
}

void damp_range(const ParticleView& p, std::size_t begin, std::size_t end, float factor) {
  for (std::size_t i = begin; i < end; i += kLanes) {
    const Lanes l{i, std::min(kLanes, end - i)};
    // A kinematic particle (w <= 0) keeps its velocity: v * 1 is v.
    const Floats f = xsimd::select(l.load(p.w) <= Floats(0.0f), Floats(1.0f), Floats(factor));
    l.store(p.vx, l.load(p.vx) * f), l.store(p.vy, l.load(p.vy) * f),
        l.store(p.vz, l.load(p.vz) * f);
  }
}

}  // namespace

void predict_positions(const ParticleView& p, float dt, const float gravity[3]) {
  // v += free g with free = 1 or 0: a free particle's increment is g, a pinned one's 0 g (a
  // signed zero, NaN for an infinite g); selecting between the two gives the same bits.
  const float g[3] = {dt * gravity[0], dt * gravity[1], dt * gravity[2]};
  const float g_pinned[3] = {0.0f * g[0], 0.0f * g[1], 0.0f * g[2]};
  simd::parallel_batches(0, p.n, kBatchesPerTask, [&](std::size_t b, std::size_t e) {
    predict_range(p, b, e, dt, g, g_pinned);
  });
}

void update_velocities(const ParticleView& p, float dt) {
  const float inv_dt = 1.0f / dt;
  simd::parallel_batches(0, p.n, kBatchesPerTask,
                         [&](std::size_t b, std::size_t e) { update_range(p, b, e, inv_dt); });
}

void damp_velocities(const ParticleView& p, float factor) {
  simd::parallel_batches(0, p.n, kBatchesPerTask,
                         [&](std::size_t b, std::size_t e) { damp_range(p, b, e, factor); });
}

}  // namespace seiche::kernels
