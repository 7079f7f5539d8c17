// Small xsimd helpers shared by the kernels (internal to kernels/): 16-byte record gathers and
// scatters (neighbor passes, colored constraint solves, packing) and the neighbor-pass loops.
//
// The neighbor passes run lane = particle: a batch holds kLanes consecutive particles (a
// NeighborGroup), and slot k of the loop processes the k-th neighbor of each of them. The
// particles' own data is one contiguous load, every lane accumulates its own sums (no horizontal
// reductions), and a lane's arithmetic does not depend on the other lanes, so results do not
// depend on how particles are grouped or on the thread count.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include <xsimd/xsimd.hpp>

#include "seiche/kernels/particle_view.hpp"

#if defined(__GNUC__)
#define SEICHE_INLINE __attribute__((always_inline))
#else
#define SEICHE_INLINE
#endif

namespace seiche::kernels::simd {

using Floats = xsimd::batch<float>;
using Mask = xsimd::batch_bool<float>;
inline constexpr std::size_t kLanes = Floats::size;

/// Hides where v comes from from the optimizer (an empty asm that "may change" it), so that it
/// neither reuses values computed from it earlier nor keeps them live: for addresses that are
/// cheaper to recompute than to keep in registers across a long computation.
template <class T>
SEICHE_INLINE inline void opaque(T& v) {
#if defined(__GNUC__)
  asm("" : "+r"(v));
#endif
}

/// The four components of kLanes Float4 records, transposed into four batches (lane l holds
/// records[index(l)]). One 16-byte load per record and a register transpose: xsimd 8's gather
/// is a scalar loop, and hardware gathers are slower than this on AVX2 anyway.
struct Gathered4 {
  Floats x, y, z, w;
};
template <class Index>
inline Gathered4 gather4(const Float4* records, const Index& index) {
#if XSIMD_WITH_AVX && !XSIMD_WITH_AVX512F
  static_assert(kLanes == 8);
  auto row = [&](std::size_t a, std::size_t b) {  // records a and b in the low and high halves
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(&records[index(a)].x)),
                                _mm_load_ps(&records[index(b)].x), 1);
  };
  const __m256 r04 = row(0, 4), r15 = row(1, 5), r26 = row(2, 6), r37 = row(3, 7);
  const __m256 t0 = _mm256_unpacklo_ps(r04, r15);  // x0 x1 y0 y1 | x4 x5 y4 y5
  const __m256 t1 = _mm256_unpackhi_ps(r04, r15);  // z0 z1 w0 w1 | z4 z5 w4 w5
  const __m256 t2 = _mm256_unpacklo_ps(r26, r37);  // x2 x3 y2 y3 | x6 x7 y6 y7
  const __m256 t3 = _mm256_unpackhi_ps(r26, r37);  // z2 z3 w2 w3 | z6 z7 w6 w7
  return {Floats(_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0))),
          Floats(_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2))),
          Floats(_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0))),
          Floats(_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2)))};
#elif XSIMD_WITH_SSE2 && !XSIMD_WITH_AVX
  static_assert(kLanes == 4);
  __m128 a = _mm_load_ps(&records[index(0)].x), b = _mm_load_ps(&records[index(1)].x),
         c = _mm_load_ps(&records[index(2)].x), d = _mm_load_ps(&records[index(3)].x);
  _MM_TRANSPOSE4_PS(a, b, c, d);
  return {Floats(a), Floats(b), Floats(c), Floats(d)};
#else
  alignas(64) float x[kLanes], y[kLanes], z[kLanes], w[kLanes];
  for (std::size_t l = 0; l < kLanes; ++l) {
    const Float4 r = records[index(l)];
    x[l] = r.x, y[l] = r.y, z[l] = r.z, w[l] = r.w;
  }
  return {Floats::load_aligned(x), Floats::load_aligned(y), Floats::load_aligned(z),
          Floats::load_aligned(w)};
#endif
}

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

/// kLanes consecutive particles [i0, i0 + kLanes) and their neighbor lists; lanes at or past n
/// are padding with an empty list. Slots k < kmin are valid in every lane; slots in
/// [kmin, kmax) are valid where k < count (neighbor(l, k) then reads a valid index whose data
/// the caller masks out).
struct NeighborGroup {
  const std::uint32_t* list[kLanes];
  std::uint32_t last[kLanes];  // count - 1, 0 for an empty list (which points at indices[0])
  Floats count;                // per-lane list length
  std::uint32_t kmin = 0, kmax = 0;
  std::size_t i0 = 0, active = 0;  // active = min(kLanes, n - i0)

  NeighborGroup(NeighborSpan nbr, std::size_t first, std::size_t n)
      : i0(first), active(std::min(kLanes, n - first)) {
    alignas(64) float c[kLanes];
    std::uint32_t lo = ~0u, hi = 0;
    for (std::size_t l = 0; l < kLanes; ++l) {
      std::uint32_t begin = 0, size = 0;
      if (l < active) begin = nbr.offsets[i0 + l], size = nbr.offsets[i0 + l + 1] - begin;
      list[l] = nbr.indices + (size > 0 ? begin : 0);
      last[l] = size > 0 ? size - 1 : 0;
      c[l] = float(size);
      lo = std::min(lo, size), hi = std::max(hi, size);
    }
    count = Floats::load_aligned(c);
    kmin = lo, kmax = hi;
  }
  bool full() const { return active == kLanes; }
  /// Neighbor k of lane l, for k < kmin.
  std::uint32_t neighbor(std::size_t l, std::uint32_t k) const { return list[l][k]; }
  /// Neighbor k of lane l, or some valid index if k is past the lane's list.
  std::uint32_t neighbor_clamped(std::size_t l, std::uint32_t k) const {
    return list[l][std::min(k, last[l])];
  }
  /// The group's own records (padding lanes repeat the last particle).
  Gathered4 own(const Float4* records) const {
    if (full()) return gather4(records + i0, [](std::size_t l) { return l; });
    return gather4(records, [&](std::size_t l) { return i0 + std::min(l, active - 1); });
  }
  /// Lane l of v to out[i0 + l] for the active lanes.
  void store(float* out, const Floats& v) const {
    if (full()) return v.store_unaligned(out + i0);
    alignas(64) float tmp[kLanes];
    v.store_aligned(tmp);
    for (std::size_t l = 0; l < active; ++l) out[i0 + l] = tmp[l];
  }
  /// out[i0 + l] for the active lanes (0 in padding lanes).
  Floats load(const float* in) const {
    if (full()) return Floats::load_unaligned(in + i0);
    alignas(64) float tmp[kLanes] = {};
    for (std::size_t l = 0; l < active; ++l) tmp[l] = in[i0 + l];
    return Floats::load_aligned(tmp);
  }
};

// Overloads the kernels' math is written against (templated on the batch type).
inline Floats vmax(const Floats& x, const Floats& y) { return xsimd::max(x, y); }
inline Floats vrsqrt(const Floats& x) { return xsimd::rsqrt(x); }
/// z - x y (one fused instruction).
inline Floats mul_sub_from(const Floats& x, const Floats& y, const Floats& z) { return xsimd::fnma(x, y, z); }
/// acc += x y (one fused instruction).
inline void accumulate(Floats& acc, const Floats& x, const Floats& y) { acc = xsimd::fma(x, y, acc); }

/// v where m is set, else 0 (a plain AND of the compare mask: cheaper than a blend).
inline Floats keep_if(const Mask& m, const Floats& v) {
#if XSIMD_WITH_AVX
  if constexpr (kLanes == 8) return Floats(_mm256_and_ps(__m256(m), __m256(v)));
#endif
  return xsimd::select(m, v, Floats(0.0f));
}

/// Runs body(neighbor records, masked, valid) over the slots of a group: first the slots valid in
/// every lane (masked = std::false_type, valid all true), then the tail (masked = std::true_type,
/// valid = lanes whose list has slot k). The records of slot k + 1 are loaded before body runs
/// on slot k, so their load latency overlaps the arithmetic. Mark body SEICHE_INLINE.
template <class Body>
SEICHE_INLINE inline void for_each_slot(const NeighborGroup& g, const Float4* records, Body&& body) {
  const Mask all(true);
  std::uint32_t k = 0;
  if (g.kmin > 0) {
    Gathered4 next = gather4(records, [&](std::size_t l) { return g.neighbor(l, 0); });
    for (; k + 1 < g.kmin; ++k) {
      const Gathered4 current = next;
      next = gather4(records, [&](std::size_t l) { return g.neighbor(l, k + 1); });
      body(current, std::false_type{}, all);
    }
    body(next, std::false_type{}, all);
    ++k;
  }
  for (; k < g.kmax; ++k) {
    const Mask valid = Floats(float(k)) < g.count;
    body(gather4(records, [&](std::size_t l) { return g.neighbor_clamped(l, k); }),
         std::true_type{}, valid);
  }
}

/// Prefetches the neighbor lists of particles [first, last) (clamped to n).
inline void prefetch_lists(NeighborSpan nbr, std::size_t first, std::size_t last, std::size_t n) {
  if (first >= n) return;
  const char* a = reinterpret_cast<const char*>(nbr.indices + nbr.offsets[first]);
  const char* b = reinterpret_cast<const char*>(nbr.indices + nbr.offsets[std::min(last, n)]);
  for (; a < b; a += 64) __builtin_prefetch(a);
}

/// kLanes consecutive particles from i, for streaming passes over SoA columns (lane = particle);
/// a partial batch is staged through a buffer, its padding lanes repeating the last particle and
/// never stored.
struct Lanes {
  std::size_t i = 0, active = 0;
  bool full() const { return active == kLanes; }
  Floats load(const float* column) const {
    if (full()) return Floats::load_unaligned(column + i);
    alignas(64) float t[kLanes];
    for (std::size_t l = 0; l < kLanes; ++l) t[l] = column[i + std::min(l, active - 1)];
    return Floats::load_aligned(t);
  }
  void store(float* column, const Floats& v) const {
    if (full()) return v.store_unaligned(column + i);
    alignas(64) float t[kLanes];
    v.store_aligned(t);
    for (std::size_t l = 0; l < active; ++l) column[i + l] = t[l];
  }
};

}  // namespace seiche::kernels::simd
