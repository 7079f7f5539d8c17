// The fluid particles within a ball, found in the fluid's grid of this substep (the store is in
// its cell order, so a cell's particles are a run of indices): for a point p and a radius r, every
// fluid particle j with |p - x_j| < r, the cells within ceil(r / cell) of p's cell in z, y, x
// order and each cell's particles in index order, a fixed order (the same bits at any thread
// count). Used by the particle contacts (cloth or shape particles against fluid), by the
// shapes' fluid boundary and by the density error's boundary (on the error probe's own grid).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "seiche/neighbor/cell_grid.hpp"
#include "seiche/particle_store.hpp"

namespace seiche {

/// Calls visit(j) for each fluid particle j of `grid` with |p - x_j| < r, x_j = (x[j], y[j], z[j])
/// (the positions the grid sorted, in its order).
template <class Visit>
void for_each_fluid_particle_within(const neighbor::CellGrid& grid, const float* xs, const float* ys,
                                    const float* zs, float x, float y, float z, float r, Visit&& visit) {
  const int cells = int(std::ceil(r / grid.spec().cell_size));
  std::int32_t c[3];
  grid.cell_of(x, y, z, c);
  const auto& d = grid.spec().dims;
  for (int cz = std::max(c[2] - cells, 0); cz <= std::min(c[2] + cells, d[2] - 1); ++cz)
    for (int cy = std::max(c[1] - cells, 0); cy <= std::min(c[1] + cells, d[1] - 1); ++cy)
      for (int cx = std::max(c[0] - cells, 0); cx <= std::min(c[0] + cells, d[0] - 1); ++cx) {
        const std::uint32_t cell = grid.cell_index(cx, cy, cz);
        for (std::uint32_t j = grid.cell_begin(cell); j < grid.cell_end(cell); ++j) {
          const float dx = x - xs[j], dy = y - ys[j], dz = z - zs[j];
          if (dx * dx + dy * dy + dz * dz < r * r) visit(j);
        }
      }
}

/// Calls visit(j) for each fluid particle j of `grid` (indices into `store`, at their predicted
/// positions px, py, pz) with |p - x_j| < r.
template <class Visit>
void for_each_fluid_particle_within(const neighbor::CellGrid& grid, const ParticleStore& store, float x, float y,
                                    float z, float r, Visit&& visit) {
  for_each_fluid_particle_within(grid, store.px.data(), store.py.data(), store.pz.data(), x, y, z, r,
                                 std::forward<Visit>(visit));
}

}  // namespace seiche
