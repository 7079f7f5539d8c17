// Mass properties of the rigid bodies' shapes (the closed forms are in body_shape.hpp).
#include "body_shape.hpp"

#include "body_mesh.hpp"

#include <numbers>

namespace seiche::rigid {

BodyShape body_shape_of(std::string_view name) {
  if (name == "sphere") return BodyShape::Sphere;
  if (name == "capsule") return BodyShape::Capsule;
  if (name == "mesh") return BodyShape::Mesh;
  return BodyShape::Box;
}

ShapeDims body_shape_def(const RigidBodyDef& def) {
  ShapeDims d{body_shape_of(def.shape),
              {double(def.size[0]), double(def.size[1]), double(def.size[2])},
              double(def.radius),
              double(def.length),
              double(def.density),
              nullptr};
  if (d.shape == BodyShape::Mesh)
    d.mesh = def.loaded_mesh ? def.loaded_mesh
                             : std::make_shared<const BodyMesh>(read_body_mesh(def.mesh, "rigid_bodies[].mesh"));
  return d;
}

MassProperties mass_properties(const ShapeDims& d) {
  constexpr double pi = std::numbers::pi;
  MassProperties p;
  switch (d.shape) {
    case BodyShape::Box: {
      const double a = d.size.x, b = d.size.y, c = d.size.z;
      p.mass = d.density * a * b * c;
      p.inertia = {p.mass / 12.0 * (b * b + c * c), p.mass / 12.0 * (a * a + c * c), p.mass / 12.0 * (a * a + b * b)};
      p.extent = 0.5 * length(d.size);
      break;
    }
    case BodyShape::Sphere: {
      const double r = d.radius;
      p.mass = d.density * 4.0 / 3.0 * pi * r * r * r;
      const double i = 0.4 * p.mass * r * r;
      p.inertia = {i, i, i};
      p.extent = r;
      break;
    }
    case BodyShape::Capsule: {
      const double r = d.radius, h = d.length;
      const double cylinder = d.density * pi * r * r * h;
      const double caps = d.density * 4.0 / 3.0 * pi * r * r * r;
      p.mass = cylinder + caps;
      const double along = 0.5 * cylinder * r * r + 0.4 * caps * r * r;
      const double across = cylinder * (h * h / 12.0 + r * r / 4.0) + caps * (0.4 * r * r + h * h / 4.0 + 0.375 * h * r);
      p.inertia = {across, along, across};
      p.extent = 0.5 * h + r;
      break;
    }
    case BodyShape::Mesh: {
      if (!d.mesh) break;  // no mesh: no mass (the reader always loads one)
      p.mass = d.density * d.mesh->volume;
      p.inertia = d.density * d.mesh->unit_inertia;
      p.extent = d.mesh->extent;
      p.principal = d.mesh->principal;
      break;
    }
  }
  return p;
}

}  // namespace seiche::rigid
