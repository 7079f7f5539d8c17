// The closed triangle set of an OBJ mesh and its check, shared by everything that needs a mesh's
// inside (a mesh collider's signed distance field, a mesh shape's voxels, a mesh rigid body's
// volume integrals). The faces as read are fanned into triangles; triangles with a repeated
// vertex are dropped (they have no area in any projection). The faces are used rather than
// `mesh.triangles`, because the reader drops zero-area triangles from `triangles`, and dropping
// a sliver from a closed mesh would open it. Closed: every undirected edge belongs to exactly two
// of the triangles. Consistently wound: each such edge is used once in each direction.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "families/cloth/cloth_mesh.hpp"

namespace seiche {

struct ClosedTriangles {
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< fanned faces without repeated vertices
  bool consistent = true;  ///< every edge used once in each direction
};

/// The mesh's closed triangle set. Throws SceneError(file, json_path, ...) when the mesh has no
/// triangles, or when it is not closed (naming its first open edge, 1-based, and how many there
/// are); std::invalid_argument for a vertex index out of range.
ClosedTriangles closed_triangles(const ClothMesh& mesh, const std::string& file, const std::string& json_path);

}  // namespace seiche
