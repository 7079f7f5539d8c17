// PackedPositions (packed_positions.hpp): the index range by a vectorized min/max over the
// columns; pack and unpack lane = particle, kLanes records transposed in registers at a time
// (simd::scatter4 and simd::gather4), in parallel blocks.
#include "seiche/kernels/packed_positions.hpp"

#include <algorithm>

#include "simd.hpp"

namespace seiche::kernels {

namespace {

using simd::Floats;
using simd::kLanes;

// body(begin, end) over the range in parallel: a grain of 4,096 records (whole batches), the
// blocks split evenly over the threads.
template <class Body>
void parallel_blocks(IndexRange range, Body&& body) {
  constexpr std::size_t kBatchesPerBlock = 4096 / kLanes;
  simd::parallel_batches(range.lo, std::size_t(range.hi) + 1, kBatchesPerBlock, body,
                         tbb::static_partitioner());
}

}  // namespace

IndexRange index_range(std::initializer_list<std::span<const std::uint32_t>> columns) {
  using seiche::simd::Ints;
  Ints vmin(~0u), vmax(0u);
  std::uint32_t lo = ~0u, hi = 0;
  bool any = false;
  for (std::span<const std::uint32_t> column : columns) {
    const std::size_t m = column.size();
    any = any || m > 0;
    std::size_t k = 0;
    for (; k + Ints::size <= m; k += Ints::size) {
      const Ints v = Ints::load_unaligned(column.data() + k);
      vmin = xsimd::min(vmin, v), vmax = xsimd::max(vmax, v);
    }
    for (; k < m; ++k) lo = std::min(lo, column[k]), hi = std::max(hi, column[k]);
  }
  if (!any) return {};
  alignas(64) std::uint32_t t[2][Ints::size];
  vmin.store_aligned(t[0]), vmax.store_aligned(t[1]);
  for (std::size_t l = 0; l < Ints::size; ++l)
    lo = std::min(lo, t[0][l]), hi = std::max(hi, t[1][l]);
  return {lo, hi};
}

void PackedPositions::reset(IndexRange range) {
  range_ = range;
  if (range.size() != capacity_) {
    capacity_ = range.size();
    records_.reset(capacity_ ? new Float4[capacity_] : nullptr);  // uninitialized: pack writes all
  }
  by_index_ = range.empty()
                  ? nullptr
                  : reinterpret_cast<Float4*>(reinterpret_cast<std::uintptr_t>(records_.get()) -
                                              std::uintptr_t(range.lo) * sizeof(Float4));
}

void PackedPositions::pack(const ParticleView& p) {
  if (range_.empty()) return;
  Float4* const r = by_index_;
  parallel_blocks(range_, [&](std::size_t i, std::size_t end) {
    for (; i + kLanes <= end; i += kLanes)
      simd::scatter4(
          r, [&](std::size_t l) { return i + l; }, Floats::load_unaligned(p.px + i),
          Floats::load_unaligned(p.py + i), Floats::load_unaligned(p.pz + i),
          Floats::load_unaligned(p.w + i));
    for (; i < end; ++i) r[i] = {p.px[i], p.py[i], p.pz[i], p.w[i]};
  });
}

void PackedPositions::unpack(const ParticleView& p) const {
  if (range_.empty()) return;
  const Float4* const r = by_index_;
  parallel_blocks(range_, [&](std::size_t i, std::size_t end) {
    for (; i + kLanes <= end; i += kLanes) {
      const simd::Gathered4 g = simd::gather4(r, [&](std::size_t l) { return i + l; });
      g.x.store_unaligned(p.px + i), g.y.store_unaligned(p.py + i), g.z.store_unaligned(p.pz + i);
    }
    for (; i < end; ++i) p.px[i] = r[i].x, p.py[i] = r[i].y, p.pz[i] = r[i].z;
  });
}

}  // namespace seiche::kernels
