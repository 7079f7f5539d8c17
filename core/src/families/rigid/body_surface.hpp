// A rigid body's surface as a triangle mesh in its body frame, for the per-frame OBJ output
// (<body name>.%04d.obj): a mesh body's own closed triangles (body_mesh.hpp), or one generated
// for the closed-form shapes, wound outward:
//   box      8 corners, 12 triangles
//   sphere   a UV sphere of kSegments meridians and 2 kRings latitude bands (poles on the y axis)
//   capsule  the sphere's two halves moved apart by the cylinder's length along y, joined by a
//            band of kSegments quads (the cylinder)
// And the OBJ text of a body at a pose: its vertices turned and moved into the world.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "rigid_math.hpp"
#include "seiche/frame_exporter.hpp"
#include "seiche/scene.hpp"

namespace seiche::rigid {

inline constexpr int kSegments = 24;  ///< meridians of a generated sphere or capsule
inline constexpr int kRings = 6;      ///< latitude bands per hemisphere

struct BodySurface {
  std::vector<Vec3d> vertices;                          ///< body frame (m)
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< wound outward
};

/// The surface of `def` in its body frame (a mesh body's from def.loaded_mesh, else its file).
BodySurface body_surface(const RigidBodyDef& def);

/// Wavefront OBJ text of the surface at `pose`: a comment naming the body, "v" lines
/// (x + R(q) v, printed as the shortest text that reads back to the same float) and
/// "f a b c" lines (1-based).
std::string encode_body_obj(const std::string& name, const BodySurface& surface, const BodyPose& pose);

}  // namespace seiche::rigid
