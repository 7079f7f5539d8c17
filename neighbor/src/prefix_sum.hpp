// Parallel exclusive prefix sum over fixed blocks (block sums, serial scan of the sums, then each
// block re-scanned from its offset). The blocks do not depend on the thread count, and integer
// sums are exact anyway, so the result is deterministic.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace seiche::neighbor::detail {

/// a[0..n) becomes its exclusive prefix sum; returns the total (in 64 bits, so a caller can
/// detect that it no longer fits the element type).
template <class T>
std::uint64_t exclusive_scan_in_place(T* a, std::size_t n) {
  constexpr std::size_t kBlock = std::size_t(1) << 15;
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  auto scan_block = [a, n](std::size_t b, std::uint64_t sum) {
    for (std::size_t i = b * kBlock, e = std::min(n, i + kBlock); i < e; ++i) {
      const T v = a[i];
      a[i] = T(sum);
      sum += v;
    }
    return sum;
  };
  if (blocks <= 1) return scan_block(0, 0);

  std::vector<std::uint64_t> block_sum(blocks + 1, 0);
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    std::uint64_t s = 0;
    for (std::size_t i = b * kBlock, e = std::min(n, i + kBlock); i < e; ++i) s += a[i];
    block_sum[b + 1] = s;
  });
  for (std::size_t b = 0; b < blocks; ++b) block_sum[b + 1] += block_sum[b];
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) { scan_block(b, block_sum[b]); });
  return block_sum[blocks];
}

}  // namespace seiche::neighbor::detail
