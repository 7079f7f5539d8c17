// Graph coloring of constraints for parallel Gauss-Seidel: constraints that share no particle
// get the same color; colors are solved one after another, the constraints of one color in
// parallel. The result depends only on the input order, so solving color by color gives the
// same bits with any thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace seiche::kernels {

struct Coloring {
  /// order[k] = input index of the k-th constraint in color order (stable inside a color).
  std::vector<std::uint32_t> order;
  /// Color c holds order[color_start[c] .. color_start[c + 1]).
  std::vector<std::uint32_t> color_start;

  std::size_t colors() const { return color_start.empty() ? 0 : color_start.size() - 1; }
};

/// Greedy coloring: constraint c touches particles[c * arity .. (c + 1) * arity), every index
/// < particle_count; each constraint takes the lowest color none of its particles uses yet.
Coloring color_constraints(std::span<const std::uint32_t> particles, std::size_t arity,
                           std::size_t particle_count);

}  // namespace seiche::kernels
