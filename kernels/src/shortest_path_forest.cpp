// Shortest-path spanning forests of distance constraints (shortest_path_forest.hpp): Dijkstra
// from all pins at once, then from the lowest unreached vertex of each piece without pins.
#include "seiche/kernels/shortest_path_forest.hpp"

#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace seiche::kernels {

void grow_shortest_path_forest(std::size_t vertices, std::span<const std::array<std::uint32_t, 2>> edges,
                               std::span<const double> edge_length, std::span<const std::uint8_t> pinned,
                               std::size_t base, std::size_t edge_base, std::span<std::uint8_t> used,
                               ForestLinks& out) {
  constexpr std::uint32_t kRoot = DistanceForest::kRoot;
  const std::size_t n = vertices;
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> neighbors(n);  // (vertex, edge)
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (used[e]) continue;
    neighbors[edges[e][0]].push_back({edges[e][1], std::uint32_t(e)});
    neighbors[edges[e][1]].push_back({edges[e][0], std::uint32_t(e)});
  }
  std::vector<double> d(n, std::numeric_limits<double>::infinity());
  std::vector<std::uint32_t> parent(n, kRoot), parent_edge(n, 0), position(n, 0);
  std::vector<std::uint8_t> settled(n, 0);
  using Item = std::pair<double, std::uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  auto grow = [&] {
    while (!queue.empty()) {
      const auto [du, u] = queue.top();
      queue.pop();
      if (settled[u] || du > d[u]) continue;
      settled[u] = 1;
      position[u] = std::uint32_t(out.particle.size());
      out.particle.push_back(std::uint32_t(base + u));
      out.parent.push_back(parent[u] == kRoot ? kRoot : position[parent[u]]);
      out.edge.push_back(parent[u] == kRoot ? 0u : std::uint32_t(edge_base + parent_edge[u]));
      if (parent[u] != kRoot) used[parent_edge[u]] = 1;
      for (const auto& [v, e] : neighbors[u]) {
        if (settled[v] || pinned[v]) continue;  // a pin is always a root
        const double dv = du + edge_length[e];
        if (dv < d[v]) d[v] = dv, parent[v] = u, parent_edge[v] = e, queue.push({dv, v});
      }
    }
  };
  for (std::size_t v = 0; v < n; ++v)
    if (pinned[v]) d[v] = 0.0, queue.push({0.0, std::uint32_t(v)});
  grow();
  for (std::size_t v = 0; v < n; ++v)
    if (!settled[v]) d[v] = 0.0, queue.push({0.0, std::uint32_t(v)}), grow();
}

std::vector<DistanceForest> make_distance_forests(std::span<ForestLinks> links,
                                                  std::span<const std::uint32_t> colored_source,
                                                  std::size_t min_vertices) {
  std::vector<std::uint32_t> colored_index(colored_source.size());
  for (std::size_t k = 0; k < colored_source.size(); ++k) colored_index[colored_source[k]] = std::uint32_t(k);
  std::vector<DistanceForest> forests;
  for (ForestLinks& raw : links) {
    for (std::size_t i = 0; i < raw.edge.size(); ++i)
      if (raw.parent[i] != DistanceForest::kRoot) raw.edge[i] = colored_index[raw.edge[i]];
    forests.push_back(make_distance_forest(raw.particle, raw.parent, raw.edge, min_vertices));
  }
  return forests;
}

}  // namespace seiche::kernels
