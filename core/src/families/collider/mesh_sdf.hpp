// Signed distance field of a closed triangle mesh (a "mesh" collider), sampled on a dense grid
// that covers the mesh's box grown by a band; negative inside.
#pragma once

#include <vector>

#include "families/cloth/cloth_mesh.hpp"
#include "seiche/kernels/sdf_grid.hpp"

namespace seiche {

struct MeshSdf {
  kernels::SdfGrid grid;       ///< grid.values points into `values`
  std::vector<float> values;

  MeshSdf() = default;
  MeshSdf(const MeshSdf&) = delete;  // grid.values points into this object's own storage
  MeshSdf& operator=(const MeshSdf&) = delete;
};

/// Builds the field of `mesh`'s triangles with sample spacing `voxel` (m, > 0) over the mesh's
/// bounding box grown by `band` (m) on every side. Exact distances (to the closest triangle)
/// within 1.5 voxels of the mesh; farther away the exact distance to a nearby triangle, never
/// less than the true distance and at most a few hundredths of a voxel more (see mesh_sdf.cpp).
/// The sign from the mesh's inside (the mesh must be closed: every edge of its faces shared by
/// exactly two triangles, else SceneError(file, mesh_path + ".file", ...) naming an open edge;
/// SceneError(file, mesh_path + ".voxel_size", ...) for a voxel <= 0 or a grid of more than 2^26
/// samples). `mesh_path` is the JSON path of the mesh object, e.g. "colliders[0].mesh".
void build_mesh_sdf(const ClothMesh& mesh, float voxel, float band, const std::string& file,
                    const std::string& mesh_path, MeshSdf& out);

}  // namespace seiche
