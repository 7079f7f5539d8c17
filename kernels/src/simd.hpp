// Small xsimd helpers shared by the neighbor-pass kernels (internal to kernels/).
#pragma once

#include <cstddef>
#include <cstdint>

#include <xsimd/xsimd.hpp>

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels::simd {

using Floats = xsimd::batch<float>;
using Ints = xsimd::batch<std::int32_t>;
using Mask = xsimd::batch_bool<float>;
inline constexpr std::size_t kLanes = Floats::size;
static_assert(Ints::size == kLanes, "float and int32 batches must have the same lane count");

/// 0, 1, 2, ... as floats: compared against a remaining count it masks a tail.
inline Floats lane_index() {
  alignas(64) static constexpr float iota[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
  static_assert(kLanes <= 16);
  return Floats::load_aligned(iota);
}

/// A batch of neighbor indices starting at k of a list of `count`; lanes past the end hold
/// `fill` (a valid index whose data the caller masks out).
inline Ints load_indices(const std::uint32_t* list, std::size_t count, std::size_t k,
                         std::int32_t fill) {
  if (k + kLanes <= count) return Ints::load_unaligned(reinterpret_cast<const std::int32_t*>(list + k));
  alignas(64) std::int32_t buffer[kLanes];
  for (std::size_t l = 0; l < kLanes; ++l)
    buffer[l] = k + l < count ? std::int32_t(list[k + l]) : fill;
  return Ints::load_aligned(buffer);
}

/// The four components of Float4 records at `index`, gathered into four batches.
struct Gathered4 {
  Floats x, y, z, w;
};
inline Gathered4 gather4(const Float4* records, const Ints& index) {
  const float* base = &records[0].x;
  const Ints at = index * 4;
  return {Floats::gather(base, at), Floats::gather(base + 1, at), Floats::gather(base + 2, at),
          Floats::gather(base + 3, at)};
}

}  // namespace seiche::kernels::simd
