// A rigid body's shape and its mass properties in closed form: mass and the inertia tensor
// about the centre of mass, diagonal in the body frame (the shapes are symmetric about the
// body's axes). With density rho:
//   box, edges a b c along x y z:  m = rho a b c,  I = m/12 [b^2 + c^2, a^2 + c^2, a^2 + b^2]
//   sphere, radius r:              m = rho 4/3 pi r^3,  I = 2/5 m r^2 on every axis
//   capsule, radius r, cylinder length h along y (a hemisphere at each end):
//     m_c = rho pi r^2 h (cylinder),  m_s = rho 4/3 pi r^3 (both caps: one sphere)
//     I_yy = m_c r^2 / 2 + 2/5 m_s r^2
//     I_xx = I_zz = m_c (h^2/12 + r^2/4) + m_s (2/5 r^2 + h^2/4 + 3/8 h r)
//   (each cap about its own centroid, 83/320 m r^2 across, moved by the parallel-axis theorem to
//   the body's centre; the terms collect to the line above).
//   mesh: m = rho V and the principal moments rho I_unit of the closed mesh's volume integrals
//   (body_mesh.hpp), in the body frame of its principal axes, turned by `principal` from the
//   mesh's own axes.
#pragma once

#include <memory>
#include <string_view>

#include "rigid_math.hpp"
#include "seiche/scene.hpp"

namespace seiche::rigid {

enum class BodyShape { Box, Sphere, Capsule, Mesh };

struct BodyMesh;

/// "box", "sphere", "capsule" or "mesh" (the key table allows no other); Box for anything else.
BodyShape body_shape_of(std::string_view name);

struct ShapeDims {
  BodyShape shape = BodyShape::Box;
  Vec3d size;           ///< box edges (m)
  double radius = 0.0;  ///< sphere, capsule (m)
  double length = 0.0;  ///< capsule cylinder (m)
  double density = 0.0; ///< kg/m^3
  std::shared_ptr<const BodyMesh> mesh = nullptr;  ///< mesh: its volume integrals
};

struct MassProperties {
  double mass = 0.0;  ///< kg
  Vec3d inertia;      ///< kg m^2, the principal moments along the body's x, y, z
  double extent = 0.0;  ///< m, the distance from the centre to the farthest point of the shape
  Quatd principal;      ///< the body frame's rotation from the shape's rest axes (a mesh's file axes)
};

/// The shape of `def`; a mesh's from def.loaded_mesh, else read from its file now.
ShapeDims body_shape_def(const RigidBodyDef& def);
MassProperties mass_properties(const ShapeDims& dims);

}  // namespace seiche::rigid

namespace seiche::detail {
using rigid::body_shape_def;
using rigid::body_shape_of;
using rigid::BodyShape;
using rigid::mass_properties;
using rigid::MassProperties;
}  // namespace seiche::detail
