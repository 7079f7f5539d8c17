// Spanning forests of a graph of distance constraints for the exact tree solve
// (distance_tree.hpp), built once: shortest-path forests (Dijkstra on the edges' lengths) grown
// from the pinned vertices, each over the edges the forests before it left. A forest grown from
// the pins follows the paths along which they hold the rest; a connected piece that no pin
// reaches grows from its lowest vertex (a free root). Used by the cloth's stretch forests (mesh
// edges) and by the raw distance constraints.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "seiche/kernels/distance_tree.hpp"

namespace seiche::kernels {

/// A forest as parent links, in the order make_distance_forest takes them (a parent before its
/// children): per position the vertex's store index, the position of its parent (or
/// DistanceForest::kRoot) and the index of the parent edge.
struct ForestLinks {
  std::vector<std::uint32_t> particle, parent, edge;
};

/// Grows one shortest-path forest over the `edges` (vertex pairs in 0 .. vertices - 1, of
/// lengths edge_length) not yet `used`, from every pinned vertex at once (a pin is always a root;
/// a piece without pins grows from its lowest vertex). Appends the vertices in the order they
/// are settled, as store indices base + v, with the position of the parent (offset by the
/// positions already in `out`) and the edge's index edge_base + e; marks the edges it takes as
/// used. Deterministic: ties are settled by the lower vertex.
void grow_shortest_path_forest(std::size_t vertices, std::span<const std::array<std::uint32_t, 2>> edges,
                               std::span<const double> edge_length, std::span<const std::uint8_t> pinned,
                               std::size_t base, std::size_t edge_base, std::span<std::uint8_t> used,
                               ForestLinks& out);

/// The DistanceForests of `links` whose edges are numbered in the order the constraints were
/// given to color_distance_constraints, which returned `colored_source` (for each colored
/// constraint its input index): the edges are renumbered to the colored constraints. Trees of
/// fewer than min_vertices vertices are dropped (make_distance_forest).
std::vector<DistanceForest> make_distance_forests(std::span<ForestLinks> links,
                                                  std::span<const std::uint32_t> colored_source,
                                                  std::size_t min_vertices = 2);

}  // namespace seiche::kernels
