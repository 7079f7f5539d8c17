// The kernels' loop helpers over the SIMD layer (simd/: seiche/simd/batch.hpp for the types and
// the rules, seiche/simd/intrinsics.hpp for the multiply-adds and the record transposes,
// seiche/simd/math.hpp for atan2), internal to kernels/: the neighbor-pass loops and the
// streaming passes over SoA columns.
//
// The neighbor passes run lane = particle: a batch holds kLanes consecutive particles (a
// NeighborGroup), and slot k of the loop processes the k-th neighbor of each of them. The
// particles' own data is one contiguous load, every lane accumulates its own sums (no horizontal
// reductions), and a lane's arithmetic does not depend on the other lanes, so results do not
// depend on how particles are grouped, on the thread count or on the SIMD width.
//
// The streaming passes run lane = particle over Lanes, in parallel over batch-aligned blocks
// (parallel_batches).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "seiche/kernels/particle_view.hpp"
#include "seiche/simd/batch.hpp"
#include "seiche/simd/intrinsics.hpp"
#include "seiche/simd/math.hpp"

namespace seiche::kernels::simd {

using seiche::simd::accumulate;
using seiche::simd::atan2;
using seiche::simd::Floats;
using seiche::simd::gather4;
using seiche::simd::Gathered4;
using seiche::simd::keep_if;
using seiche::simd::kLanes;
using seiche::simd::Mask;
using seiche::simd::mul_sub_from;
using seiche::simd::multiply_add;
using seiche::simd::negate;
using seiche::simd::opaque;
using seiche::simd::scatter4;

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

/// body(begin, end) over the particles [first, last) in parallel, cut at multiples of kLanes
/// from `first` (so that only the last batch of all is partial); batches_per_task is TBB's grain
/// size in batches, `partitioner` TBB's partitioner. A body computes each particle the same way
/// whatever the cut, so any thread count gives the same bits.
template <class Body, class Partitioner = tbb::auto_partitioner>
void parallel_batches(std::size_t first, std::size_t last, std::size_t batches_per_task,
                      Body&& body, Partitioner&& partitioner = {}) {
  if (last <= first) return;
  const std::size_t batches = (last - first + kLanes - 1) / kLanes;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, batches, batches_per_task),
      [&](const tbb::blocked_range<std::size_t>& r) {
        body(first + r.begin() * kLanes, std::min(last, first + r.end() * kLanes));
      },
      partitioner);
}

}  // namespace seiche::kernels::simd
