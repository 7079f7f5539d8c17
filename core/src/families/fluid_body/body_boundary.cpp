// Sampling a rigid body's boundary particles and their volumes (the formulas are in
// body_boundary.hpp).
#include "body_boundary.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "families/rigid/body_shape.hpp"
#include "families/rigid/body_solid.hpp"
#include "seiche/kernels/sph_kernels.hpp"

namespace seiche::fluid_body {

namespace {

double component(Vec3d v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

// The lattice's cell centres inside the solid and within h of its surface.
std::vector<Vec3d> boundary_sites(const rigid::ShapeDims& dims, const rigid::SolidSurface& solid, double extent,
                                  double spacing, double h) {
  Vec3d step{spacing, spacing, spacing}, start;
  int count[3];
  if (dims.shape == rigid::BodyShape::Box) {
    for (int a = 0; a < 3; ++a) count[a] = std::max(1, int(std::lround(component(dims.size, a) / spacing)));
    step = {dims.size.x / count[0], dims.size.y / count[1], dims.size.z / count[2]};
    start = {-0.5 * dims.size.x + 0.5 * step.x, -0.5 * dims.size.y + 0.5 * step.y, -0.5 * dims.size.z + 0.5 * step.z};
  } else {
    const int half = int(std::ceil(extent / spacing));
    for (int a = 0; a < 3; ++a) count[a] = 2 * half;
    const double first = (0.5 - double(half)) * spacing;
    start = {first, first, first};
  }
  std::vector<Vec3d> sites;
  for (int k = 0; k < count[2]; ++k)
    for (int j = 0; j < count[1]; ++j)
      for (int i = 0; i < count[0]; ++i) {
        const Vec3d p{start.x + i * step.x, start.y + j * step.y, start.z + k * step.z};
        rigid::SurfacePenetration inside;
        if (rigid::penetration(solid, p, 0.0, inside) && inside.depth < h) sites.push_back(p);
      }
  if (sites.empty()) sites.push_back({0.0, 0.0, 0.0});  // smaller than a cell
  return sites;
}

}  // namespace

double boundary_lattice_size(const rigid::ShapeDims& dims, double extent, double spacing) {
  if (dims.shape == rigid::BodyShape::Box)
    return std::max(1.0, std::round(dims.size.x / spacing)) * std::max(1.0, std::round(dims.size.y / spacing)) *
           std::max(1.0, std::round(dims.size.z / spacing));
  const double side = 2.0 * std::ceil(extent / spacing);
  return side * side * side;
}

double boundary_site_bound(const rigid::ShapeDims& dims, double extent, double spacing, double h) {
  const double lattice = boundary_lattice_size(dims, extent, spacing);
  constexpr double pi = std::numbers::pi;
  // The solid's volume grown (or shrunk, r < 0: none) to radius r: a ball, or a capsule's.
  const auto round_volume = [&](double r) {
    if (!(r > 0.0)) return 0.0;
    return 4.0 / 3.0 * pi * r * r * r + (dims.shape == rigid::BodyShape::Capsule ? pi * r * r * dims.length : 0.0);
  };
  double sites = lattice;
  if (dims.shape == rigid::BodyShape::Box) {
    // Along each axis, the cells whose centres (i + 1/2) step lie deeper than h from both faces.
    double interior = 1.0;
    for (int a = 0; a < 3; ++a) {
      const double size = component(dims.size, a);
      const double n = std::max(1.0, std::round(size / spacing)), step = size / n;
      const double first = std::ceil(h / step - 0.5), last = std::floor(n - 0.5 - h / step);
      interior *= std::max(0.0, last - first + 1.0);
    }
    sites = lattice - interior;
  } else if (dims.shape != rigid::BodyShape::Mesh) {
    const double d = 0.5 * std::sqrt(3.0) * spacing;
    const double shell = round_volume(dims.radius + d) - round_volume(dims.radius - h - d);
    sites = std::min(lattice, std::ceil(shell / (spacing * spacing * spacing)));
  }
  return std::max(1.0, sites);
}

double boundary_grid_cell_bound(const rigid::ShapeDims& dims, double extent, double h) {
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    double width = 2.0 * extent;
    if (dims.shape == rigid::BodyShape::Box) width = component(dims.size, a);
    if (dims.shape == rigid::BodyShape::Sphere) width = 2.0 * dims.radius;
    if (dims.shape == rigid::BodyShape::Capsule) width = 2.0 * dims.radius + (a == 1 ? dims.length : 0.0);
    cells *= std::floor(width / h) + 1.0;
  }
  return cells;
}

BodyBoundary sample_body_boundary(const RigidBodyDef& def, std::shared_ptr<const MeshSdf> field, double spacing,
                                  double h) {
  BodyBoundary b;
  const rigid::ShapeDims dims = rigid::body_shape_def(def);
  b.extent = rigid::mass_properties(dims).extent;
  if (dims.shape == rigid::BodyShape::Mesh) b.field = std::move(field);
  b.solid = rigid::body_solid(dims, b.field.get());
  std::vector<Vec3d> sites = boundary_sites(dims, b.solid, b.extent, spacing, h);

  // The grid over the sites' box, cell h; sites counted into cells in site order.
  b.h = h;
  Vec3d hi = sites[0];
  b.lo = sites[0];
  for (const Vec3d& p : sites) {
    b.lo = {std::min(b.lo.x, p.x), std::min(b.lo.y, p.y), std::min(b.lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  for (int a = 0; a < 3; ++a) b.dims[a] = int(std::floor((component(hi, a) - component(b.lo, a)) / h)) + 1;
  const auto cell_of = [&](Vec3d p) {
    int c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp(int(std::floor((component(p, a) - component(b.lo, a)) / h)), 0, b.dims[a] - 1);
    return (std::size_t(c[2]) * std::size_t(b.dims[1]) + std::size_t(c[1])) * std::size_t(b.dims[0]) + std::size_t(c[0]);
  };
  const std::size_t cells = std::size_t(b.dims[0]) * std::size_t(b.dims[1]) * std::size_t(b.dims[2]);
  b.cell_start.assign(cells + 1, 0);
  for (const Vec3d& p : sites) ++b.cell_start[cell_of(p) + 1];
  for (std::size_t c = 0; c < cells; ++c) b.cell_start[c + 1] += b.cell_start[c];
  std::vector<std::uint32_t> next(b.cell_start.begin(), b.cell_start.end() - 1);
  b.sites.resize(sites.size());
  for (const Vec3d& p : sites) b.sites[next[cell_of(p)]++] = p;

  // psi_b = 1 / sum_k W(|x_b - x_k|) over the body's own sites (b included: W(0) > 0).
  const kernels::SphKernel kernel{float(h)};
  b.psi.resize(b.sites.size());
  for (std::size_t s = 0; s < b.sites.size(); ++s) {
    double sum = 0.0;
    b.for_each_site_near(b.sites[s], [&](std::uint32_t k) {
      const Vec3d d = b.sites[s] - b.sites[k];
      sum += double(kernel.poly6(float(dot(d, d))));
    });
    b.psi[s] = sum > 0.0 ? 1.0 / sum : 0.0;
    b.reach = std::max(b.reach, length(b.sites[s]) + h);
  }
  return b;
}

}  // namespace seiche::fluid_body
