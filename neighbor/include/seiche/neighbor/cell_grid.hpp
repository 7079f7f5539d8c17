// Uniform grid over a box, built GPU-style: a cell key per particle, a parallel counting sort by
// key, and per-cell [begin, end) ranges into the sorted order.
//
// The grid covers `box_min .. box_max` (usually the scene's domain, slightly enlarged). Particles
// outside it, or with non-finite coordinates, are clamped into the border cells: the domain is
// unbounded in the sense that such particles are still found by every query (a clamped cell
// coordinate never moves two particles within `cell_size` of each other more than one cell
// apart), they merely cost more. When box / cell_size would give more cells than `max_cells`,
// the cell size grows (never shrinks below the requested size), so memory stays bounded.
//
// Determinism: the sorted order depends only on the input (particles of one cell keep their
// input order), never on the thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace seiche::neighbor {

struct GridSpec {
  float origin[3] = {0, 0, 0};  ///< world position of cell (0,0,0)'s lower corner (m)
  float cell_size = 1.0f;       ///< >= the query radius (m)
  std::int32_t dims[3] = {1, 1, 1};

  std::size_t cell_count() const { return std::size_t(dims[0]) * dims[1] * dims[2]; }
};

/// A grid over [box_min, box_max] with cells of at least `min_cell_size`, at most `max_cells`
/// cells in all (the cell size grows to respect that). box_min <= box_max and min_cell_size > 0.
/// (The cell size is min_cell_size * (1 + 2^-19) at least: that margin absorbs float rounding, so
/// a query with radius = min_cell_size never misses a pair two cell indices apart. Non-finite or
/// swapped bounds and a non-positive cell size are repaired rather than rejected.)
GridSpec make_grid_spec(const float box_min[3], const float box_max[3], float min_cell_size,
                        std::size_t max_cells = std::size_t(1) << 24);

/// Counting sort of particles by cell. `build` does not move any particle: it computes `order()`,
/// the permutation a caller applies to its own arrays (sorted[k] = unsorted[order[k]]). After
/// the caller has applied it, cell c holds the sorted particles [cell_begin(c), cell_end(c)).
class CellGrid {
 public:
  /// x, y, z: n positions. `in_grid` (nullable): particles with in_grid[i] == 0 take no part in
  /// the grid; they are sorted after all others, keep their relative order, and belong to no
  /// cell (num_in_grid() counts the others).
  void build(const GridSpec& spec, const float* x, const float* y, const float* z,
             const std::uint8_t* in_grid, std::size_t n);

  const GridSpec& spec() const { return spec_; }
  std::span<const std::uint32_t> order() const { return order_; }
  std::size_t num_in_grid() const { return num_in_grid_; }

  /// Cell coordinate (clamped) of a point; the same function the build uses.
  void cell_of(float x, float y, float z, std::int32_t out[3]) const;
  std::uint32_t cell_index(std::int32_t cx, std::int32_t cy, std::int32_t cz) const {
    return std::uint32_t((std::size_t(cz) * spec_.dims[1] + cy) * spec_.dims[0] + cx);
  }
  /// Sorted-index range of cell c (valid after the caller applied order()).
  std::uint32_t cell_begin(std::uint32_t c) const { return cell_start_[c]; }
  std::uint32_t cell_end(std::uint32_t c) const { return cell_start_[c + 1]; }

  /// Bytes held by this grid's arrays (for the memory-per-particle figure).
  std::size_t bytes() const;

 private:
  GridSpec spec_;
  std::size_t num_in_grid_ = 0;
  std::vector<std::uint32_t> keys_;        // cell key per input particle
  std::vector<std::uint32_t> order_;       // sorted -> input index
  std::vector<std::uint32_t> cell_start_;  // cell_count + 1 prefix offsets
};

}  // namespace seiche::neighbor
