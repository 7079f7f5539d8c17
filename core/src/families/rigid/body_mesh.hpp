// A rigid body shaped by a closed OBJ triangle mesh: its mass properties from the mesh, and the
// mesh in the body frame.
//
// The volume integrals over the solid come from the divergence theorem as a sum over the closed
// triangles (Mirtich 1996; Eberly, "Polyhedral Mass Properties"): each outward-wound triangle
// (a, b, c) and a reference point r spans a tetrahedron of signed volume v = a'.(b' x c') / 6
// (a' = a - r, ...), and the tetrahedra's signed sums are the solid's integrals:
//   V       = sum v
//   int x   = sum v (a' + b' + c') / 4                                   (r + int x / V: centre)
//   int x_i x_j = sum v / 20 [a'_i a'_j + b'_i b'_j + c'_i c'_j + s_i s_j],  s = a' + b' + c'
// (the tetrahedron's second moments with its fourth vertex at r). About the centre of mass c
// (c' = c - r): S = int x'x'^T - V c' c'^T, and per unit density the inertia tensor is
// I = tr(S) Id - S. r is the centre of the mesh's bounding box, so that a mesh far from its
// file's origin loses no digits to cancellation.
//
// The body frame: its origin at the centre of mass, its axes the principal axes of I (Eigen's
// SelfAdjointEigenSolver), ordered and signed to lie closest to the mesh's own x, y, z (a proper
// rotation; the identity when I is diagonal to 1e-12 of its trace, so an axis-aligned box mesh
// has the frame of a box body).
//
// Refused (SceneError naming the OBJ and `<mesh path>.file`): a mesh that is not closed
// (closed_mesh.hpp), one wound inconsistently (an edge used twice in the same direction: no
// inside), one without volume (|V| at most 1e-9 of its bounding box's diagonal cubed), and one
// wound inward (V negative).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "rigid_math.hpp"
#include "seiche/scene.hpp"

namespace seiche {
struct ClothMesh;
}

namespace seiche::rigid {

/// The integrals of a closed, outward-wound triangle mesh per unit density.
struct MeshIntegrals {
  double volume = 0.0;                       ///< m^3 (negative for an inward-wound mesh)
  Vec3d centre;                              ///< centre of mass, in the vertices' coordinates
  std::array<std::array<double, 3>, 3> inertia{};  ///< about the centre, per unit density (m^5)
};

MeshIntegrals mesh_integrals(std::span<const Vec3d> vertices, std::span<const std::array<std::uint32_t, 3>> triangles);

struct BodyMesh {
  std::vector<Vec3d> vertices;  ///< body frame: centre of mass at the origin, principal axes
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< the closed set, wound outward
  double volume = 0.0;          ///< m^3
  Vec3d unit_inertia;           ///< principal moments per unit density (m^5)
  Vec3d centre;                 ///< the centre of mass in the scaled file's coordinates (m)
  Quatd principal;              ///< body frame to the scaled file's axes
  double extent = 0.0;          ///< the farthest vertex from the centre of mass (m)
  /// The size and FNV-1a 64 hash of the OBJ's bytes as read (input_fingerprint.hpp).
  std::uint64_t source_bytes = 0, source_fnv1a64 = 0;
};

/// The body mesh of `mesh` (vertices as in the file) scaled by `scale`. `file` (the OBJ) and
/// `mesh_path` (e.g. "rigid_bodies[0].mesh") name it in errors; see above for what is refused.
BodyMesh make_body_mesh(const ClothMesh& mesh, double scale, const std::string& file, const std::string& mesh_path);

/// Reads `def.file` (the OBJ, its vertices as in the file) and makes its body mesh scaled by
/// `def.scale` (def.translate is not used: a body is placed by its centre of mass).
BodyMesh read_body_mesh(const ClothMeshDef& def, const std::string& mesh_path);

}  // namespace seiche::rigid
