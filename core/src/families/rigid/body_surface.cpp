// A rigid body's surface mesh and its OBJ text (contract in body_surface.hpp).
#include "body_surface.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "body_mesh.hpp"
#include "body_shape.hpp"

namespace seiche::rigid {

namespace {

BodySurface box_surface(Vec3d size) {
  BodySurface s;
  const Vec3d h = 0.5 * size;
  for (int k = 0; k < 8; ++k) s.vertices.push_back({k & 1 ? h.x : -h.x, k & 2 ? h.y : -h.y, k & 4 ? h.z : -h.z});
  // Each face as a quad, counter-clockwise seen from outside.
  constexpr std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    s.triangles.push_back({q[0], q[1], q[2]});
    s.triangles.push_back({q[0], q[2], q[3]});
  }
  return s;
}

// A sphere of `radius` whose upper half is moved up and lower half down by `half_length` (a
// capsule; a sphere for 0). Rings from the top down; each ring kSegments vertices at angles
// 2 pi j / kSegments about y, x = r cos, z = -r sin (counter-clockwise seen from +y).
BodySurface round_surface(double radius, double half_length) {
  BodySurface s;
  constexpr double pi = std::numbers::pi;
  std::vector<std::array<double, 2>> rings;  // (ring radius, y) below the top pole
  for (int i = 1; i <= kRings; ++i) {
    const double latitude = 0.5 * pi - i * 0.5 * pi / kRings;
    rings.push_back({radius * std::cos(latitude), radius * std::sin(latitude) + half_length});
  }
  for (int i = half_length > 0.0 ? 0 : 1; i < kRings; ++i) {
    const double latitude = -i * 0.5 * pi / kRings;
    rings.push_back({radius * std::cos(latitude), radius * std::sin(latitude) - half_length});
  }
  s.vertices.push_back({0.0, radius + half_length, 0.0});
  for (const auto& [r, y] : rings)
    for (int j = 0; j < kSegments; ++j) {
      const double a = 2.0 * pi * j / kSegments;
      s.vertices.push_back({r * std::cos(a), y, -r * std::sin(a)});
    }
  s.vertices.push_back({0.0, -radius - half_length, 0.0});
  const std::uint32_t n = kSegments, bottom = std::uint32_t(s.vertices.size() - 1);
  const auto at = [&](std::size_t ring, std::uint32_t j) { return std::uint32_t(1 + ring * n + j % n); };
  for (std::uint32_t j = 0; j < n; ++j) s.triangles.push_back({0, at(0, j), at(0, j + 1)});
  for (std::size_t ring = 0; ring + 1 < rings.size(); ++ring)
    for (std::uint32_t j = 0; j < n; ++j) {
      s.triangles.push_back({at(ring, j), at(ring + 1, j), at(ring + 1, j + 1)});
      s.triangles.push_back({at(ring, j), at(ring + 1, j + 1), at(ring, j + 1)});
    }
  const std::size_t last = rings.size() - 1;
  for (std::uint32_t j = 0; j < n; ++j) s.triangles.push_back({bottom, at(last, j + 1), at(last, j)});
  return s;
}

}  // namespace

BodySurface body_surface(const RigidBodyDef& def) {
  const ShapeDims d = body_shape_def(def);
  switch (d.shape) {
    case BodyShape::Box:
      return box_surface(d.size);
    case BodyShape::Sphere:
      return round_surface(d.radius, 0.0);
    case BodyShape::Capsule:
      return round_surface(d.radius, 0.5 * d.length);
    case BodyShape::Mesh:
      break;
  }
  BodySurface s;
  if (d.mesh) s.vertices = d.mesh->vertices, s.triangles = d.mesh->triangles;
  return s;
}

std::string encode_body_obj(const std::string& name, const BodySurface& surface, const BodyPose& pose) {
  const Vec3d x{pose.position[0], pose.position[1], pose.position[2]};
  const Quatd q{pose.orientation[0], pose.orientation[1], pose.orientation[2], pose.orientation[3]};
  std::string out = fmt::format("# seiche rigid body {}: {} vertices, {} triangles\n", name, surface.vertices.size(),
                                surface.triangles.size());
  auto it = std::back_inserter(out);
  for (const Vec3d& v : surface.vertices) {
    const Vec3d p = x + rotate(q, v);
    fmt::format_to(it, "v {} {} {}\n", float(p.x), float(p.y), float(p.z));
  }
  for (const auto& t : surface.triangles) fmt::format_to(it, "f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  return out;
}

}  // namespace seiche::rigid
