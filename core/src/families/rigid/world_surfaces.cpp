// The static world's surfaces for rigid-body contacts (the formulas are in world_surfaces.hpp).
#include "world_surfaces.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace seiche::rigid {

namespace {

Vec3d to_d(const Vec3& v) { return {double(v[0]), double(v[1]), double(v[2])}; }

double component(Vec3d v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }
Vec3d axis_vector(int a, double sign) {
  return {a == 0 ? sign : 0.0, a == 1 ? sign : 0.0, a == 2 ? sign : 0.0};
}

// Out of the ball of radius `reach` around c (up, +y, where p is at c).
bool out_of_ball(Vec3d p, Vec3d c, double reach, SurfacePenetration& out) {
  const Vec3d d = p - c;
  const double len = length(d);
  if (!(reach - len > 0.0)) return false;
  out.depth = reach - len;
  out.normal = len > 1e-12 ? (1.0 / len) * d : Vec3d{0.0, 1.0, 0.0};
  return true;
}

}  // namespace

WorldSurfaces::WorldSurfaces(const SceneDef& scene, std::span<const std::shared_ptr<const MeshSdf>> mesh_fields) {
  const auto is_mesh = [](const ColliderDef& c) { return c.shape == ColliderDef::Shape::Mesh; };
  const auto mesh_colliders = std::size_t(std::count_if(scene.colliders.begin(), scene.colliders.end(), is_mesh));
  const auto missing = [](const std::shared_ptr<const MeshSdf>& field) { return !field; };
  if (mesh_fields.size() != mesh_colliders || std::any_of(mesh_fields.begin(), mesh_fields.end(), missing))
    throw std::invalid_argument("WorldSurfaces: " + std::to_string(mesh_colliders) +
                                " mesh colliders need as many fields");
  // The domain's walls: planes facing in, lower then upper, x then y then z.
  const Vec3d lo = to_d(scene.domain.min), hi = to_d(scene.domain.max);
  for (int a = 0; a < 3; ++a)
    for (double sign : {1.0, -1.0}) {
      Surface s;
      s.a = sign > 0.0 ? lo : hi;
      s.b = axis_vector(a, sign);
      s.friction = scene.domain.friction;
      surfaces_.push_back(s);
    }
  for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
    const ColliderDef& c = scene.colliders[k];
    Surface s;
    s.shape = c.shape;
    s.friction = c.friction;
    switch (c.shape) {
      case ColliderDef::Shape::Plane: s.a = to_d(c.point), s.b = normalized_or_zero(to_d(c.normal)); break;
      case ColliderDef::Shape::Box: s.a = to_d(c.box.min), s.b = to_d(c.box.max); break;
      case ColliderDef::Shape::Sphere: s.a = to_d(c.center), s.radius = c.radius; break;
      case ColliderDef::Shape::Capsule: s.a = to_d(c.end_a), s.b = to_d(c.end_b), s.radius = c.radius; break;
      case ColliderDef::Shape::Mesh:
        mesh_sdfs_.push_back(mesh_fields[mesh_sdfs_.size()]);
        s.sdf = mesh_sdfs_.back().get();
        break;
    }
    surfaces_.push_back(s);
  }
}

bool penetration(const SolidSurface& s, Vec3d p, double r, SurfacePenetration& out) {
  switch (s.shape) {
    case ColliderDef::Shape::Plane: {
      const double depth = r - dot(p - s.a, s.b);
      if (!(depth > 0.0)) return false;
      out.depth = depth, out.normal = s.b;
      return true;
    }
    case ColliderDef::Shape::Sphere: return out_of_ball(p, s.a, s.radius + r, out);
    case ColliderDef::Shape::Capsule: {
      const Vec3d ab = s.b - s.a;
      const double ab2 = dot(ab, ab);
      const double t = ab2 > 1e-24 ? std::clamp(dot(p - s.a, ab) / ab2, 0.0, 1.0) : 0.0;
      return out_of_ball(p, s.a + t * ab, s.radius + r, out);
    }
    case ColliderDef::Shape::Box: {
      double best = INFINITY;
      int best_axis = 0;
      double best_sign = 0.0;
      for (int a = 0; a < 3; ++a) {
        const double to_min = component(p, a) - (component(s.a, a) - r);
        const double to_max = (component(s.b, a) + r) - component(p, a);
        if (!(to_min > 0.0) || !(to_max > 0.0)) return false;  // outside on this axis
        if (to_min < best) best = to_min, best_axis = a, best_sign = -1.0;
        if (to_max < best) best = to_max, best_axis = a, best_sign = 1.0;
      }
      out.depth = best, out.normal = axis_vector(best_axis, best_sign);
      return true;
    }
    case ColliderDef::Shape::Mesh: {
      // Outside the field's box (a ball's radius may reach farther than the field's band), from
      // the box's nearest point c: sdf(p) <= sdf(c) + |p - c|, equal where the mesh's nearest
      // point lies straight across the band (a face the ball is above).
      const kernels::SdfGrid& grid = s.sdf->grid;
      double clamped[3] = {p.x, p.y, p.z};
      for (int a = 0; a < 3; ++a)
        clamped[a] = std::clamp(clamped[a], double(grid.origin[a]),
                                double(grid.origin[a]) + double(grid.voxel) * double(grid.dims[a] - 1));
      const double outside = length(p - Vec3d{clamped[0], clamped[1], clamped[2]});
      // Beyond the ball's reach of the box: no contact. A point (r = 0) inside the box has
      // outside = 0 = r and is asked (with outside < r, a vertex or a box corner never touched a
      // mesh, and the fluid boundary found no site inside a mesh body).
      if (!(outside <= r)) return false;
      float distance = 0.0f, n[3];
      if (!grid.sample(float(clamped[0]), float(clamped[1]), float(clamped[2]), distance, n)) return false;
      const double depth = r - (double(distance) + outside);
      if (!(depth > 0.0)) return false;
      out.depth = depth, out.normal = normalized_or_zero({double(n[0]), double(n[1]), double(n[2])});
      return true;
    }
  }
  return false;
}

}  // namespace seiche::rigid
