// The neighbor stage of the substep: the uniform grid and the neighbor lists of the particles
// that take part in neighbor passes (fluid), in sorted order: after Simulation::find_neighbors
// those particles are store indices [0, count()).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "seiche/neighbor/cell_grid.hpp"
#include "seiche/neighbor/neighbor_list.hpp"
#include "seiche/kernels/particle_view.hpp"

namespace seiche {

struct Neighborhood {
  float radius = 0.0f;                 ///< query radius (m): the fluid's kernel radius
  neighbor::GridSpec spec;
  neighbor::CellGrid grid;
  neighbor::NeighborList list;
  std::vector<std::uint8_t> in_grid;   ///< per particle, rebuilt every substep

  std::size_t count() const { return grid.num_in_grid(); }
  /// Builds the grid over positions (x, y, z) of `phase`'s n particles; the fluid particles take
  /// part (in_grid), the others are sorted after them.
  void build_grid(const float* x, const float* y, const float* z, const std::uint32_t* phase, std::size_t n);
  kernels::NeighborSpan span() const { return {list.offsets.data(), list.indices.data()}; }
};

}  // namespace seiche
