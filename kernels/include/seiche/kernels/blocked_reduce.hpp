// A reduction whose result does not depend on the thread count: the range [0, n) is cut into
// blocks of a fixed size, each block is reduced on its own in index order (the blocks in
// parallel), and the block results are combined serially in block order:
//   result = combine(...combine(combine(identity, r_0), r_1)..., r_{B-1}),
//   r_b = reduce_block(b * block, min(n, (b + 1) * block)),  B = ceil(n / block).
// (A partitioner-dependent tbb::parallel_reduce would give different float sums with different
// thread counts.) Used by the kernels' error metrics and core's frame metrics alike.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include <tbb/parallel_for.h>

namespace seiche::kernels {

/// The block size of every blocked reduction in Seiche today (particles or constraints).
inline constexpr std::size_t kReduceBlock = 4096;

/// reduce_block(begin, end) -> T reduces one block; combine(T& acc, const T& block) merges.
template <class T, class ReduceBlock, class Combine>
T blocked_reduce(std::size_t n, T identity, ReduceBlock&& reduce_block, Combine&& combine,
                 std::size_t block = kReduceBlock) {
  const std::size_t blocks = (n + block - 1) / block;
  std::vector<T> partial(blocks, identity);
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    partial[b] = reduce_block(b * block, std::min(n, (b + 1) * block));
  });
  T result = identity;
  for (const T& p : partial) combine(result, p);
  return result;
}

}  // namespace seiche::kernels
