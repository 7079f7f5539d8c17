// A uniform grid over the rigid bodies' bounding balls, so that a fluid particle visits only the
// bodies that may reach it, not every body of the scene (the fluid-body passes run per fluid
// particle and per iteration: on 100 boxes over a pool of 240k particles, one thread, the three
// passes took 1.10 s a frame with a ball test per body and particle, 0.28 s with this grid; the
// fluid's own passes 0.40 s; docs/performance.md).
//
// Built per pass from the bodies' centres c_k and reaches R_k (the ball within which body k can
// touch a particle): cells of edge a = max_k R_k / 2 (measured on 100 boxes over a pool: 2 max R
// left many bodies in a cell and took twice as long), grown by 1.25 at a time while the grid
// would have more than kCellsPerBody cells per body (bodies far apart would otherwise ask for a
// grid of empty cells between them), over the bounding box of the balls. Cell (i, j, l)
// lists, in ascending k, every body whose ball's bounding box overlaps it. A point's candidates
// are its cell's list: every body whose ball holds the point is in it, and the order is the
// scene's, so a pass that skips the others visits the same bodies in the same order as a loop
// over all bodies with the ball test (the same bits). A point outside the grid has none.
// Not neighbor::CellGrid: that sorts points into one cell each, while a body's ball spans many
// cells and must be listed in each.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "families/rigid/rigid_math.hpp"

namespace seiche::fluid_body {

class BodyGrid {
 public:
  /// Rebuilds the grid for balls (centres[k], reaches[k]); the two spans have the same size.
  void build(std::span<const rigid::Vec3d> centres, std::span<const double> reaches);

  /// The bodies (ascending) whose balls may hold p: a superset of those that do.
  std::span<const std::uint32_t> candidates(rigid::Vec3d p) const;

 private:
  static constexpr std::size_t kCellsPerBody = 256;
  rigid::Vec3d lo_;
  double inverse_cell_ = 0.0;
  int dims_[3] = {0, 0, 0};
  std::vector<std::uint32_t> start_;   // per cell, its first entry in bodies_; one more at the end
  std::vector<std::uint32_t> bodies_;  // the cells' lists, cell after cell
};

}  // namespace seiche::fluid_body
