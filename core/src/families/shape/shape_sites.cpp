// The lattice sites of a shape-matched body (contract in shape_sites.hpp).
#include "shape_sites.hpp"

#include <algorithm>
#include <cmath>

#include "families/cloth/cloth_mesh.hpp"
#include "families/collider/mesh_sdf.hpp"
#include "families/lattice.hpp"

namespace seiche {

namespace {

// The sphere's sites in cell order, each passed to site(cell, position).
template <class Site>
void for_each_sphere_site(const ShapeDef& s, Site&& site) {
  const double h = s.spacing, r = s.radius;
  const std::int32_t n = std::int32_t(std::floor(r / h));
  for (std::int32_t k = -n; k <= n; ++k)
    for (std::int32_t j = -n; j <= n; ++j)
      for (std::int32_t i = -n; i <= n; ++i) {
        const double x = i * h, y = j * h, z = k * h;
        if (x * x + y * y + z * z > r * r) continue;
        site(std::array<std::int32_t, 3>{i, j, k},
             Vec3{float(s.center[0] + x), float(s.center[1] + y), float(s.center[2] + z)});
      }
}

}  // namespace

double mesh_lattice_samples(const ClothMesh& mesh, float spacing) {
  double total = 1.0;
  for (int a = 0; a < 3; ++a) {
    float lo = INFINITY, hi = -INFINITY;
    for (const Vec3& x : mesh.positions) lo = std::min(lo, x[a]), hi = std::max(hi, x[a]);
    total *= std::ceil((double(hi) - lo) / spacing) + 2.0;
  }
  return total;
}

ShapeSites voxelize_mesh(const ClothMesh& mesh, float spacing, const std::string& file, const std::string& mesh_path) {
  MeshSdf sdf;
  build_mesh_sdf(mesh, spacing, 0.5f * spacing, file, mesh_path, sdf);
  const kernels::SdfGrid& g = sdf.grid;
  ShapeSites sites;
  sites.source_bytes = mesh.source_bytes, sites.source_fnv1a64 = mesh.source_fnv1a64;
  std::size_t index = 0;
  for (std::int32_t k = 0; k < g.dims[2]; ++k)
    for (std::int32_t j = 0; j < g.dims[1]; ++j)
      for (std::int32_t i = 0; i < g.dims[0]; ++i, ++index) {
        if (!(sdf.values[index] < 0.0f)) continue;
        sites.cell.push_back({i, j, k});
        sites.position.push_back({float(double(g.origin[0]) + double(i) * g.voxel),
                                  float(double(g.origin[1]) + double(j) * g.voxel),
                                  float(double(g.origin[2]) + double(k) * g.voxel)});
      }
  return sites;
}

ShapeSites shape_sites(const ShapeDef& s, const std::string& json_path) {
  ShapeSites sites;
  switch (s.kind) {
    case ShapeDef::Kind::Box: {
      const auto n = lattice_counts(s.box, s.spacing);
      std::size_t index = 0;
      for_each_lattice_site(s.box, s.spacing, [&](float x, float y, float z) {
        const std::size_t i = index % n[0], j = index / n[0] % n[1], k = index / (n[0] * n[1]);
        sites.cell.push_back({std::int32_t(i), std::int32_t(j), std::int32_t(k)});
        sites.position.push_back({x, y, z});
        ++index;
      });
      break;
    }
    case ShapeDef::Kind::Sphere:
      for_each_sphere_site(s, [&](const std::array<std::int32_t, 3>& cell, const Vec3& x) {
        sites.cell.push_back(cell);
        sites.position.push_back(x);
      });
      break;
    case ShapeDef::Kind::Mesh: {
      if (s.loaded_sites) return *s.loaded_sites;
      const std::string mesh_path = json_path + ".mesh";
      const ClothMesh mesh = read_obj_mesh(s.mesh.file, s.mesh, mesh_path);
      return voxelize_mesh(mesh, s.spacing, s.mesh.file, mesh_path);
    }
  }
  return sites;
}

std::size_t shape_site_count(const ShapeDef& s) {
  switch (s.kind) {
    case ShapeDef::Kind::Box:
      return lattice_size(s.box, s.spacing);
    case ShapeDef::Kind::Sphere: {
      std::size_t count = 0;
      for_each_sphere_site(s, [&](const auto&, const auto&) { ++count; });
      return count;
    }
    case ShapeDef::Kind::Mesh:
      return s.loaded_sites ? s.loaded_sites->size() : shape_sites(s, "shapes").size();
  }
  return 0;
}

}  // namespace seiche
