// Neighbor lists in CSR form, built from a CellGrid whose order() the caller has already
// applied to the positions (so cells are contiguous index ranges).
//
// neighbors of sorted particle i: indices[offsets[i] .. offsets[i+1]), every j != i in the grid
// with |x_i - x_j|^2 < radius^2, in increasing j (a fixed, thread-count independent order).
// Particles outside the grid (in_grid == 0 at build) have empty lists and appear in none.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "seiche/neighbor/cell_grid.hpp"

namespace seiche::neighbor {

struct NeighborList {
  std::vector<std::uint32_t> offsets;  ///< n + 1 entries
  std::vector<std::uint32_t> indices;  ///< offsets[n] entries

  std::size_t size() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  std::size_t bytes() const;
};

/// radius <= grid.spec().cell_size. x, y, z are the sorted positions (n = grid size), the very
/// values build() saw, reordered. (A larger radius is also correct, scanning more cells, but
/// slower. Particles with a non-finite coordinate get no neighbors and are no one's neighbor.)
void build_neighbor_list(const CellGrid& grid, const float* x, const float* y, const float* z,
                         std::size_t n, float radius, NeighborList& out);

/// Bytes of scratch that build_neighbor_list keeps between calls so that a steady-state call
/// allocates nothing: per concurrent call, 32 work blocks' staging lists (at most ~1024
/// particles' lists each) and candidate buffers. Not included in NeighborList::bytes().
std::size_t neighbor_list_scratch_bytes();

}  // namespace seiche::neighbor
