// The fluid block the benchmarks share: n^3 particles on a lattice of spacing s, compressed by
// 2 % (so that density constraints are active as in a real solve) and jittered by +-1 % of s,
// optionally sorted by grid cell of the kernel radius h, as the simulation keeps a fluid.
#pragma once

#include <random>
#include <vector>

#include "seiche/neighbor/cell_grid.hpp"

namespace seiche::bench {

/// Appends the n^3 lattice positions to x, y, z (x fastest), drawing the jitter from rng.
inline void append_jittered_lattice(int n, float s, std::mt19937& rng, std::vector<float>& x, std::vector<float>& y,
                                    std::vector<float>& z) {
  std::uniform_real_distribution<float> jitter(-0.01f * s, 0.01f * s);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        x.push_back(0.98f * (i + 0.5f) * s + jitter(rng));
        y.push_back(0.98f * (j + 0.5f) * s + jitter(rng));
        z.push_back(0.98f * (k + 0.5f) * s + jitter(rng));
      }
}

/// Reorders x, y, z by cell of a grid of cell size h over the cube [0, side]^3. Returns the grid,
/// whose cell ranges describe the sorted order (what build_neighbor_list takes).
inline neighbor::CellGrid sort_by_cell(float side, float h, std::vector<float>& x, std::vector<float>& y, std::vector<float>& z) {
  const std::size_t count = x.size();
  const float lo[3] = {0, 0, 0}, hi[3] = {side, side, side};
  neighbor::CellGrid grid;
  grid.build(neighbor::make_grid_spec(lo, hi, h), x.data(), y.data(), z.data(), nullptr, count);
  const auto order = grid.order();
  for (auto* column : {&x, &y, &z}) {
    std::vector<float> sorted(count);
    for (std::size_t k = 0; k < count; ++k) sorted[k] = (*column)[order[k]];
    column->swap(sorted);
  }
  return grid;
}

}  // namespace seiche::bench
