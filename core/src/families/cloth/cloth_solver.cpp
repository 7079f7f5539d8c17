#include "cloth_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>

#include <fmt/format.h>

#include "seiche/kernels/blocked_reduce.hpp"
#include "seiche/kernels/dihedral_bending.hpp"
#include "seiche/kernels/shortest_path_forest.hpp"
#include "seiche/phase.hpp"

namespace seiche {

namespace {

constexpr std::size_t kTethersPerVertex = 4;  // the nearest pinned vertices a vertex is tied to

double distance(const Vec3& a, const Vec3& b) {
  const double dx = double(a[0]) - b[0], dy = double(a[1]) - b[1], dz = double(a[2]) - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

bool inside(const Vec3& p, const BoxDef& b) {
  for (int a = 0; a < 3; ++a)
    if (p[a] < b.min[a] || p[a] > b.max[a]) return false;
  return true;
}

// Shortest path lengths along the mesh edges from `source` to every vertex (Dijkstra): a
// geodesic distance that is never shorter than the true one, so a tether is never too tight.
std::vector<double> edge_path_distances(const ClothShape& shape, std::uint32_t source,
                                        const std::vector<std::vector<std::uint32_t>>& neighbors) {
  const auto& x = shape.mesh.positions;
  std::vector<double> d(x.size(), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, std::uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  d[source] = 0.0;
  queue.push({0.0, source});
  while (!queue.empty()) {
    const auto [du, u] = queue.top();
    queue.pop();
    if (du > d[u]) continue;
    for (std::uint32_t v : neighbors[u]) {
      const double dv = du + distance(x[u], x[v]);
      if (dv < d[v]) d[v] = dv, queue.push({dv, v});
    }
  }
  return d;
}

}  // namespace

ClothShape build_cloth_shape(const ClothDef& cloth, std::size_t index, const std::string& file) {
  const std::string path = fmt::format("cloths[{}]", index);
  ClothShape s;
  if (cloth.loaded_mesh && cloth.loaded_topology) {  // built once by the scene loader
    s.mesh = *cloth.loaded_mesh;
    s.topology = *cloth.loaded_topology;
  } else if (cloth.mesh) {
    s.mesh = read_obj_mesh(cloth.mesh->file, *cloth.mesh, path + ".mesh");
    s.topology = build_topology(s.mesh, cloth.mesh->file, path + ".mesh.file");
  } else {
    s.mesh = make_sheet(*cloth.sheet, file, path + ".sheet");
    s.topology = build_topology(s.mesh, file, path + ".sheet");
  }
  return s;
}

ClothSolver::ClothSolver(const SceneDef& scene) : scene_cloths_(scene.cloths) {
  for (std::size_t c = 0; c < scene_cloths_.size(); ++c) {
    shapes_.push_back(build_cloth_shape(scene_cloths_[c], c, scene.name));
    total_vertices_ += shapes_.back().mesh.vertex_count();
    radius_.push_back(0.5f * scene_cloths_[c].thickness);
  }
}

ClothSolver::~ClothSolver() = default;

void ClothSolver::create(ParticleStore& store, std::size_t first, const kernels::ParticleView& view) {
  std::vector<std::uint32_t> edge_i, edge_j, hinge_dihedral, hinge_isometric;
  std::vector<float> edge_rest, edge_compliance, bend_dihedral, bend_isometric;
  std::vector<kernels::ForestLinks> raw_forests;
  std::size_t base = first;
  for (std::size_t c = 0; c < shapes_.size(); ++c) {
    const ClothDef& def = scene_cloths_[c];
    const ClothMesh& mesh = shapes_[c].mesh;
    const ClothTopology& topo = shapes_[c].topology;
    const std::size_t n = mesh.vertex_count();
    first_id_.push_back(std::int32_t(base));

    // Pins: listed indices and the vertices inside pin_box.
    std::vector<std::uint8_t> pinned(n, 0);
    for (int p : def.pins) pinned[std::size_t(p)] = 1;
    if (def.pin_box)
      for (std::size_t v = 0; v < n; ++v) pinned[v] |= inside(mesh.positions[v], *def.pin_box) ? 1 : 0;

    // Mass: mass_per_area times the area a vertex owns; a vertex in no triangle gets the mean.
    double area_sum = 0.0;
    std::size_t with_area = 0;
    for (double a : topo.vertex_area)
      if (a > 0.0) area_sum += a, ++with_area;
    const double mean_area = with_area ? area_sum / double(with_area) : 1.0;
    for (std::size_t v = 0; v < n; ++v) {
      const std::size_t k = base + v;
      const Vec3& x = mesh.positions[v];
      store.x[k] = x[0], store.y[k] = x[1], store.z[k] = x[2];
      store.vx[k] = def.velocity[0], store.vy[k] = def.velocity[1], store.vz[k] = def.velocity[2];
      const double area = topo.vertex_area[v] > 0.0 ? topo.vertex_area[v] : mean_area;
      store.w[k] = pinned[v] ? 0.0f : float(1.0 / (def.mass_per_area * area));
      store.phase[k] = make_phase(Material::Cloth, std::uint32_t(c));
      store.radius[k] = radius_[c];
    }

    for (const auto& e : topo.edges) {
      edge_i.push_back(std::uint32_t(base + e[0]));
      edge_j.push_back(std::uint32_t(base + e[1]));
      edge_rest.push_back(float(distance(mesh.positions[e[0]], mesh.positions[e[1]])));
      edge_compliance.push_back(def.stretch_compliance);
    }
    const bool isometric = def.bending == "isometric";
    auto& hinge_list = isometric ? hinge_isometric : hinge_dihedral;
    auto& compliance_list = isometric ? bend_isometric : bend_dihedral;
    for (const auto& h : topo.hinges) {
      for (std::uint32_t v : h) hinge_list.push_back(std::uint32_t(base + v));
      compliance_list.push_back(def.bend_compliance);
    }
    if (def.tethers) build_tethers(c, base, pinned);
    // Shortest-path forests of the edges on their rest lengths, each over the edges the previous
    // ones left (kernels/shortest_path_forest.hpp).
    std::vector<std::uint8_t> used(topo.edges.size(), 0);
    // By default (the key absent) one forest for a cloth with pins, none without.
    const bool has_pins = std::find(pinned.begin(), pinned.end(), std::uint8_t(1)) != pinned.end();
    const int forests = def.stretch_forests.value_or(has_pins ? 1 : 0);
    if (raw_forests.size() < std::size_t(forests)) raw_forests.resize(std::size_t(forests));
    std::vector<double> edge_length;
    if (forests > 0)
      for (const auto& e : topo.edges) edge_length.push_back(distance(mesh.positions[e[0]], mesh.positions[e[1]]));
    for (int k = 0; k < forests; ++k)
      kernels::grow_shortest_path_forest(n, topo.edges, edge_length, pinned, base,
                                         edge_i.size() - topo.edges.size(), used, raw_forests[std::size_t(k)]);
    base += n;
  }
  const std::vector<std::uint32_t> source =
      kernels::color_distance_constraints(edge_i, edge_j, edge_rest, edge_compliance, view.n, stretch_);
  forests_ = kernels::make_distance_forests(raw_forests, source);
  if (!forests_.empty()) tension_.assign(stretch_.size(), 0.0f);
  if (!bend_dihedral.empty()) kernels::build_dihedral_bending(hinge_dihedral, bend_dihedral, view, dihedral_);
  if (!bend_isometric.empty())
    kernels::build_isometric_bending(hinge_isometric, bend_isometric, view, isometric_);
}

kernels::IndexRange ClothSolver::packed_range() const {
  const kernels::Hinges& iso = isometric_.hinges;
  return kernels::index_range({stretch_.i, stretch_.j, dihedral_.a, dihedral_.b, dihedral_.c, dihedral_.d,
                               iso.a, iso.b, iso.c, iso.d});
}

// Each free vertex is tied to its kTethersPerVertex nearest pinned vertices of the same cloth, at
// their rest distance: straight-line for a generated (flat) sheet, along the edges for a mesh.
void ClothSolver::build_tethers(std::size_t c, std::size_t base, std::span<const std::uint8_t> pinned) {
  const ClothShape& shape = shapes_[c];
  const auto& x = shape.mesh.positions;
  const std::size_t n = x.size();
  std::vector<std::uint32_t> pins;
  for (std::size_t v = 0; v < n; ++v)
    if (pinned[v]) pins.push_back(std::uint32_t(v));
  if (pins.empty()) return;

  // rest[p][v]: rest distance from pin p to vertex v.
  std::vector<std::vector<double>> rest(pins.size());
  if (scene_cloths_[c].sheet) {
    for (std::size_t p = 0; p < pins.size(); ++p) {
      rest[p].resize(n);
      for (std::size_t v = 0; v < n; ++v) rest[p][v] = distance(x[pins[p]], x[v]);
    }
  } else {
    std::vector<std::vector<std::uint32_t>> neighbors(n);
    for (const auto& e : shape.topology.edges) neighbors[e[0]].push_back(e[1]), neighbors[e[1]].push_back(e[0]);
    for (std::size_t p = 0; p < pins.size(); ++p) rest[p] = edge_path_distances(shape, pins[p], neighbors);
  }

  if (tethers_.start.empty()) tethers_.start.push_back(0);
  std::vector<std::uint32_t> nearest(pins.size());
  for (std::size_t v = 0; v < n; ++v) {
    if (pinned[v]) continue;
    std::iota(nearest.begin(), nearest.end(), 0u);
    const std::size_t keep = std::min(kTethersPerVertex, pins.size());
    std::partial_sort(nearest.begin(), nearest.begin() + std::ptrdiff_t(keep), nearest.end(),
                      [&](std::uint32_t a, std::uint32_t b) {
                        return rest[a][v] != rest[b][v] ? rest[a][v] < rest[b][v] : a < b;
                      });
    std::size_t added = 0;
    for (std::size_t k = 0; k < keep; ++k) {
      const double length = rest[nearest[k]][v];
      if (!std::isfinite(length)) continue;  // in another connected piece of the mesh
      tethers_.anchor.push_back(std::uint32_t(base + pins[nearest[k]]));
      tethers_.max_length.push_back(float(length));
      ++added;
    }
    if (added == 0) continue;
    tethers_.particle.push_back(std::uint32_t(base + v));
    tethers_.start.push_back(std::uint32_t(tethers_.anchor.size()));
  }
}

bool ClothSolver::adjacent(std::size_t c, std::uint32_t u, std::uint32_t v) const {
  if (u == v) return true;
  const ClothTopology& t = shapes_[c].topology;
  const auto begin = t.adjacent.begin() + t.adjacent_start[u];
  const auto end = t.adjacent.begin() + t.adjacent_start[u + 1];
  return std::binary_search(begin, end, v);
}

// XPBD starts every substep's multipliers at 0. The colored solves do that in the substep's first
// iteration (kernels::Multipliers::Restart), so nothing is reset here, except for the forests:
// they solve the edges first, from their multipliers at 0, and their geometric stiffness uses the
// multipliers of the substep before.
void ClothSolver::begin_substep() {
  if (forests_.empty()) return;
  tension_.swap(stretch_.lambda);
  stretch_.lambda.assign(tension_.size(), 0.0f);
}

// The forests first: they carry the load to the pins; then Gauss-Seidel over all edges.
void ClothSolver::solve_stretch_forests(const kernels::ParticleView& p, float dt) {
  for (kernels::DistanceForest& f : forests_) kernels::solve_distance_forest(p, stretch_, f, dt, tension_.data());
}

void ClothSolver::solve_stretch(const kernels::PackedPositions& packed, float dt, int iteration) {
  const bool first_solve = iteration == 0 && forests_.empty();
  kernels::solve_distance_constraints(
      packed, stretch_, dt, first_solve ? kernels::Multipliers::Restart : kernels::Multipliers::Accumulate);
}

std::span<const float> ClothSolver::stretch_multipliers() const {
  return forests_.empty() ? std::span<const float>() : std::span<const float>(stretch_.lambda);
}

void ClothSolver::restore_stretch_multipliers(std::span<const float> saved) {
  if (forests_.empty() || saved.size() != stretch_.lambda.size()) return;
  std::copy(saved.begin(), saved.end(), stretch_.lambda.begin());
}

void ClothSolver::solve_bending(const kernels::PackedPositions& packed, float dt, int iteration) {
  const auto start =
      iteration == 0 ? kernels::Multipliers::Restart : kernels::Multipliers::Accumulate;
  if (dihedral_.size()) kernels::solve_dihedral_bending(packed, dihedral_, dt, start);
  if (isometric_.size()) kernels::solve_isometric_bending(packed, isometric_, dt, start);
}

void ClothSolver::solve_tethers(const kernels::ParticleView& p) { kernels::solve_tethers(p, tethers_); }

void ClothSolver::remap(std::span<const std::uint32_t> new_index) {
  for (auto& k : stretch_.i) k = new_index[k];
  for (auto& k : stretch_.j) k = new_index[k];
  dihedral_.remap(new_index);
  isometric_.hinges.remap(new_index);
  tethers_.remap(new_index);
  for (auto& f : forests_) f.remap(new_index);
}

ClothError ClothSolver::measure(const kernels::ParticleView& p) const {
  ClothError e;
  // |l - l0| / l0 per edge (kernels::edge_strain; rest lengths of a valid mesh are > 0), in fixed
  // blocks.
  struct Strain {
    double sum = 0.0, max = 0.0;
  };
  const std::size_t m = stretch_.size();
  const Strain strain = kernels::blocked_reduce(
      m, Strain{},
      [&](std::size_t begin, std::size_t end) {
        Strain s;
        for (std::size_t k = begin; k < end; ++k) {
          const double rel =
              kernels::edge_strain(p, stretch_.i[k], stretch_.j[k], stretch_.rest_length[k]);
          s.sum += rel;
          s.max = std::max(s.max, rel);
        }
        return s;
      },
      [](Strain& acc, const Strain& s) { acc.sum += s.sum, acc.max = std::max(acc.max, s.max); });
  e.strain_mean = m ? strain.sum / double(m) : 0.0;
  e.strain_max = strain.max;
  const auto d = kernels::bending_error(p, dihedral_);
  const auto i = kernels::bending_error(p, isometric_.hinges);
  const double nd = double(dihedral_.size()), ni = double(isometric_.size());
  if (nd + ni > 0) e.bending_mean = (d.mean * nd + i.mean * ni) / (nd + ni);
  e.bending_max = std::max(d.max, i.max);
  return e;
}

}  // namespace seiche
