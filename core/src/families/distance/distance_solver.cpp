#include "distance_solver.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "seiche/kernels/shortest_path_forest.hpp"

namespace seiche {

namespace {

// A tree of one edge is left to the colored sweep, which solves it exactly already (its ends move
// along the edge in the ratio of their inverse masses, whatever the geometric stiffness): a lone
// pair, like the seed's worked example, runs as without forests.
constexpr std::size_t kMinTreeVertices = 3;

// For each edge, whether its connected component has a loop (more edges than vertices − 1).
std::vector<std::uint8_t> edges_in_loops(std::size_t vertices, std::span<const std::array<std::uint32_t, 2>> edges) {
  std::vector<std::uint32_t> root(vertices);
  std::iota(root.begin(), root.end(), 0u);
  auto find = [&](std::uint32_t v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  std::vector<std::uint8_t> loop(vertices, 0);  // per component root, after the merges
  for (const auto& e : edges) {
    const std::uint32_t a = find(e[0]), b = find(e[1]);
    if (a == b) {
      loop[a] = 1;  // this edge closes a loop
    } else {
      root[b] = a;
      loop[a] |= loop[b];
    }
  }
  std::vector<std::uint8_t> in_loop(edges.size());
  for (std::size_t k = 0; k < edges.size(); ++k) in_loop[k] = loop[find(edges[k][0])];
  return in_loop;
}

}  // namespace

DistanceSolver::DistanceSolver(std::span<const std::uint32_t> i, std::span<const std::uint32_t> j,
                               std::span<const float> rest_length,
                               std::span<const float> compliance,
                               const kernels::ParticleView& p, std::optional<int> forests) {
  std::vector<float> rest(rest_length.begin(), rest_length.end());
  for (std::size_t k = 0; k < rest.size(); ++k) {
    if (rest[k] >= 0.0f) continue;
    const float dx = p.x[i[k]] - p.x[j[k]], dy = p.y[i[k]] - p.y[j[k]], dz = p.z[i[k]] - p.z[j[k]];
    rest[k] = std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  const std::vector<std::uint32_t> source =
      kernels::color_distance_constraints(i, j, rest, compliance, p.n, constraints_);
  const int count = forests.value_or(1);
  if (count <= 0 || rest.empty()) return;

  // Shortest-path forests on the rest lengths over the particles the constraints use (store
  // indices 0 .. vertices - 1 at build time), grown from those pinned now. By default (the key
  // absent) the pieces with loops keep Gauss-Seidel alone: their edges count as taken.
  std::size_t vertices = 0;
  std::vector<std::array<std::uint32_t, 2>> edges(rest.size());
  std::vector<double> edge_length(rest.size());
  for (std::size_t k = 0; k < rest.size(); ++k) {
    edges[k] = {i[k], j[k]};
    edge_length[k] = rest[k];
    vertices = std::max<std::size_t>(vertices, std::max(i[k], j[k]) + std::size_t(1));
  }
  std::vector<std::uint8_t> pinned(vertices), used(rest.size(), 0);
  for (std::size_t v = 0; v < vertices; ++v) pinned[v] = p.w[v] > 0.0f ? 0 : 1;
  if (!forests) used = edges_in_loops(vertices, edges);
  std::vector<kernels::ForestLinks> links(static_cast<std::size_t>(count));
  for (kernels::ForestLinks& forest : links)
    kernels::grow_shortest_path_forest(vertices, edges, edge_length, pinned, 0, 0, used, forest);
  for (kernels::DistanceForest& f : kernels::make_distance_forests(links, source, kMinTreeVertices))
    if (f.trees() > 0) forests_.push_back(std::move(f));
  if (!forests_.empty()) tension_.assign(constraints_.size(), 0.0f);
}

void DistanceSolver::begin_substep() {
  if (!forests_.empty()) tension_.swap(constraints_.lambda);
  std::fill(constraints_.lambda.begin(), constraints_.lambda.end(), 0.0f);
}

// The forests carry the load to the pins; Gauss-Seidel over every constraint follows (solve).
void DistanceSolver::solve_forests(const kernels::ParticleView& p, float dt) {
  for (kernels::DistanceForest& f : forests_) kernels::solve_distance_forest(p, constraints_, f, dt, tension_.data());
}

void DistanceSolver::remap(std::span<const std::uint32_t> new_index) {
  for (auto& k : constraints_.i) k = new_index[k];
  for (auto& k : constraints_.j) k = new_index[k];
  for (auto& f : forests_) f.remap(new_index);
}

std::span<const float> DistanceSolver::multipliers() const {
  return forests_.empty() ? std::span<const float>() : std::span<const float>(constraints_.lambda);
}

void DistanceSolver::restore_multipliers(std::span<const float> saved) {
  if (forests_.empty() || saved.size() != constraints_.lambda.size()) return;
  std::copy(saved.begin(), saved.end(), constraints_.lambda.begin());
}

}  // namespace seiche
