// Colored constraint solves vectorized lane = constraint (internal to kernels/): the distance
// constraints and both bending models.
//
// Colors run one after another; inside a color, kLanes consecutive constraints form a batch, the
// batches run in parallel. A batch gathers its constraints' particles (predicted positions and
// inverse masses), the family's step computes every lane's correction, and the new positions
// are scattered back. No two constraints of a color share a particle, so the lanes of a batch
// and the batches of a color never touch the same particle. The last batch of a color is
// padded by repeating its last constraint; padding lanes compute like the others and are not
// stored. Every constraint thus goes through the same lane arithmetic (no scalar tail, no
// horizontal operation), and the result is bit-identical with any thread count.
//
// The particles are packed for the solve as (px, py, pz, w) records, so that a lane's particle
// is one 16-byte load and one 16-byte store (gathering and scattering three SoA columns costs
// twice as much), and unpacked at the end.
//
// The families' steps are templates on the number type T (float or Floats), with the small
// vector type and overloads below, so that they read as the scalar formulas they are; the
// solves instantiate them with Floats. sqrt, division and the basic operations are correctly
// rounded in both, so T = float gives the same bits lane for lane (atan2 aside).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <type_traits>
#include <utility>

#include "seiche/kernels/particle_view.hpp"
#include "simd.hpp"

namespace seiche::kernels::colored {

using simd::Floats;
using simd::kLanes;

template <class T>
struct V3 {
  T x, y, z;
};
template <class T>
inline V3<T> operator+(const V3<T>& u, const V3<T>& v) {
  return {u.x + v.x, u.y + v.y, u.z + v.z};
}
template <class T>
inline V3<T> operator-(const V3<T>& u, const V3<T>& v) {
  return {u.x - v.x, u.y - v.y, u.z - v.z};
}
template <class T>
inline V3<T> operator*(const V3<T>& u, const T& s) {
  return {u.x * s, u.y * s, u.z * s};
}
template <class T>
inline T dot(const V3<T>& u, const V3<T>& v) {
  return u.x * v.x + u.y * v.y + u.z * v.z;
}
template <class T>
inline V3<T> cross(const V3<T>& u, const V3<T>& v) {
  return {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
}

/// The comparison result of T: bool for float, a lane mask for Floats.
template <class T>
using MaskOf = std::conditional_t<std::is_same_v<T, float>, bool, simd::Mask>;
inline float select(bool m, float a, float b) { return m ? a : b; }
inline Floats select(const simd::Mask& m, const Floats& a, const Floats& b) {
  return xsimd::select(m, a, b);
}
inline float vsqrt(float x) { return std::sqrt(x); }  // both correctly rounded: same bits
inline Floats vsqrt(const Floats& x) { return xsimd::sqrt(x); }

/// kLanes consecutive constraints [k0, k0 + active) of one color.
struct Batch {
  std::size_t k0 = 0, active = 0;
  bool full() const { return active == kLanes; }
  /// Constraint of lane l: padding lanes repeat the last active constraint.
  std::size_t at(std::size_t l) const { return k0 + std::min(l, active - 1); }
  /// column[k0 + l] per lane.
  Floats load(const float* column) const {
    if (full()) return Floats::load_unaligned(column + k0);
    alignas(64) float t[kLanes];
    for (std::size_t l = 0; l < kLanes; ++l) t[l] = column[at(l)];
    return Floats::load_aligned(t);
  }
  /// Lane l of v to column[k0 + l], active lanes only.
  void store(float* column, const Floats& v) const {
    if (full()) return v.store_unaligned(column + k0);
    alignas(64) float t[kLanes];
    v.store_aligned(t);
    for (std::size_t l = 0; l < active; ++l) column[k0 + l] = t[l];
  }
};

/// Writes lane l of (x, y, z, w) to records[index(l)] for l < active: the transpose of
/// simd::gather4, one 16-byte store per record.
template <class Index>
SEICHE_INLINE inline void scatter4(Float4* records, const Index& index, const Floats& x,
                                   const Floats& y, const Floats& z, const Floats& w,
                                   std::size_t active = kLanes) {
#if XSIMD_WITH_AVX && !XSIMD_WITH_AVX512F
  static_assert(kLanes == 8);
  const __m256 t0 = _mm256_unpacklo_ps(x, y);  // x0 y0 x1 y1 | x4 y4 x5 y5
  const __m256 t1 = _mm256_unpackhi_ps(x, y);  // x2 y2 x3 y3 | x6 y6 x7 y7
  const __m256 t2 = _mm256_unpacklo_ps(z, w);  // z0 w0 z1 w1 | z4 w4 z5 w5
  const __m256 t3 = _mm256_unpackhi_ps(z, w);  // z2 w2 z3 w3 | z6 w6 z7 w7
  const __m256 r0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));  // records 0 | 4
  const __m256 r1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));  // records 1 | 5
  const __m256 r2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));  // records 2 | 6
  const __m256 r3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));  // records 3 | 7
  auto put = [&](std::size_t l, __m128 v) {
    if (l < active) _mm_store_ps(&records[index(l)].x, v);
  };
  put(0, _mm256_castps256_ps128(r0)), put(1, _mm256_castps256_ps128(r1));
  put(2, _mm256_castps256_ps128(r2)), put(3, _mm256_castps256_ps128(r3));
  put(4, _mm256_extractf128_ps(r0, 1)), put(5, _mm256_extractf128_ps(r1, 1));
  put(6, _mm256_extractf128_ps(r2, 1)), put(7, _mm256_extractf128_ps(r3, 1));
#else
  alignas(64) float tx[kLanes], ty[kLanes], tz[kLanes], tw[kLanes];
  x.store_aligned(tx), y.store_aligned(ty), z.store_aligned(tz), w.store_aligned(tw);
  for (std::size_t l = 0; l < active; ++l) records[index(l)] = {tx[l], ty[l], tz[l], tw[l]};
#endif
}

/// The particles a solve touches, packed as (px, py, pz, w) records for 16-byte gathers and
/// scatters: only the index range [lo, hi] the constraints use (a store may hold much more than
/// one cloth). by_index[i] is particle i's record: records shifted by lo, so that the constraints'
/// store indices address it directly (no subtraction per lane). It is formed through an integer
/// (implementation-defined, not undefined, on the flat address spaces we target) and only
/// dereferenced at indices in [lo, hi].
struct PackedParticles {
  std::unique_ptr<Float4[]> records;
  Float4* by_index = nullptr;
  std::uint32_t lo = 0, hi = 0;

  PackedParticles(const ParticleView& p, std::span<const std::uint32_t* const> columns,
                  std::size_t m) {
    using Ints = xsimd::batch<std::uint32_t>;
    Ints vmin(~0u), vmax(0u);
    std::uint32_t min_index = ~0u, max_index = 0;
    for (const std::uint32_t* column : columns) {
      std::size_t k = 0;
      for (; k + Ints::size <= m; k += Ints::size) {
        const Ints v = Ints::load_unaligned(column + k);
        vmin = xsimd::min(vmin, v), vmax = xsimd::max(vmax, v);
      }
      for (; k < m; ++k)
        min_index = std::min(min_index, column[k]), max_index = std::max(max_index, column[k]);
    }
    alignas(64) std::uint32_t t[2][Ints::size];
    vmin.store_aligned(t[0]), vmax.store_aligned(t[1]);
    for (std::size_t l = 0; l < Ints::size; ++l)
      min_index = std::min(min_index, t[0][l]), max_index = std::max(max_index, t[1][l]);
    lo = min_index, hi = max_index;
    records.reset(new Float4[std::size_t(hi - lo) + 1]);  // uninitialized: every record is written
    by_index = reinterpret_cast<Float4*>(reinterpret_cast<std::uintptr_t>(records.get()) -
                                         std::uintptr_t(lo) * sizeof(Float4));
    Float4* const r = by_index;
    parallel_blocks([&](std::size_t i, std::size_t end) {
      for (; i + kLanes <= end; i += kLanes)
        scatter4(
            r, [&](std::size_t l) { return i + l; }, Floats::load_unaligned(p.px + i),
            Floats::load_unaligned(p.py + i), Floats::load_unaligned(p.pz + i),
            Floats::load_unaligned(p.w + i));
      for (; i < end; ++i) r[i] = {p.px[i], p.py[i], p.pz[i], p.w[i]};
    });
  }
  /// Writes the positions back to px, py, pz.
  void unpack(const ParticleView& p) const {
    const Float4* const r = by_index;
    parallel_blocks([&](std::size_t i, std::size_t end) {
      for (; i + kLanes <= end; i += kLanes) {
        const simd::Gathered4 g = simd::gather4(r, [&](std::size_t l) { return i + l; });
        g.x.store_unaligned(p.px + i), g.y.store_unaligned(p.py + i), g.z.store_unaligned(p.pz + i);
      }
      for (; i < end; ++i) p.px[i] = r[i].x, p.py[i] = r[i].y, p.pz[i] = r[i].z;
    });
  }

 private:
  template <class Body>
  void parallel_blocks(Body&& body) const {
    constexpr std::size_t kBlock = 4096;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(lo, std::size_t(hi) + 1, kBlock),
        [&](const auto& r) { body(r.begin(), r.end()); }, tbb::static_partitioner());
  }
};

/// body(std::integral_constant<std::size_t, s>) for s = 0 .. N - 1.
template <std::size_t N, class Body>
SEICHE_INLINE inline void for_each_slot(Body&& body) {
  [&]<std::size_t... S>(std::index_sequence<S...>) {
    (body(std::integral_constant<std::size_t, S>{}), ...);
  }
  (std::make_index_sequence<N>{});
}

/// One batch: gather, step, scatter. Full is known at compile time, so a full batch (all but at
/// most one per color) runs without lane checks; a partial one runs the same lane arithmetic.
/// Everything arrives by value: the 16-byte stores may alias anything, and values in registers
/// need no reload after them.
template <bool Full, std::size_t N, class Step>
SEICHE_INLINE inline void solve_batch(Float4* records, std::array<const std::uint32_t*, N> vertex,
                                      Batch batch, Step step) {
  V3<Floats> x[N], dp[N];
  Floats w[N];
  // Slot by slot, unrolled at compile time (constant indices keep x, w, dp in registers).
  for_each_slot<N>([&](auto s) {
    const std::uint32_t* column = vertex[s];
    const simd::Gathered4 g =
        Full ? simd::gather4(records, [&](std::size_t l) { return column[batch.k0 + l]; })
             : simd::gather4(records, [&](std::size_t l) { return column[batch.at(l)]; });
    x[s] = {g.x, g.y, g.z};
    w[s] = g.w;
  });
  step(batch, x, w, dp);
  for_each_slot<N>([&](auto s) {
    const std::uint32_t* column = vertex[s];
    scatter4(
        records, [&](std::size_t l) { return column[batch.k0 + l]; }, x[s].x + dp[s].x,
        x[s].y + dp[s].y, x[s].z + dp[s].z, w[s], Full ? kLanes : batch.active);
  });
}

/// Solves every color of a colored family of N-particle constraints: vertex[s] is the column of
/// the constraints' s-th particle index. step(batch, positions x[N], inverse masses w[N],
/// corrections dp[N]) computes the lanes' corrections (and updates the family's own columns,
/// such as lambda, through batch.load and batch.store); x + dp is then scattered back. step is
/// copied by value into every task: give it the raw pointers it needs, captured by value.
template <std::size_t N, class Step>
void solve_colored(const ParticleView& p, std::span<const std::uint32_t> color_start,
                   const std::array<const std::uint32_t*, N>& vertex, const Step& step) {
  const std::size_t m = color_start.empty() ? 0 : color_start.back();
  if (m == 0) return;
  PackedParticles packed(p, vertex, m);
  Float4* const records = packed.by_index;
  for (std::size_t color = 0; color + 1 < color_start.size(); ++color) {
    const std::size_t begin = color_start[color], end = color_start[color + 1];
    const std::size_t full_batches = (end - begin) / kLanes;
    // A static partition: every color is split alike, so each thread keeps working on the same
    // part of the mesh (constraints are stored in mesh order inside a color) and its particles
    // stay in its core's cache from one color to the next.
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, full_batches, 16),
        [=](const auto& r) {
          for (std::size_t bi = r.begin(); bi != r.end(); ++bi)
            solve_batch<true>(records, vertex, Batch{begin + bi * kLanes, kLanes}, step);
        },
        tbb::static_partitioner());
    const std::size_t tail = begin + full_batches * kLanes;
    if (tail < end) solve_batch<false>(records, vertex, Batch{tail, end - tail}, step);
  }
  packed.unpack(p);
}

}  // namespace seiche::kernels::colored
