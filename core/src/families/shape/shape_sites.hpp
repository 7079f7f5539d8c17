// The lattice sites of a shape-matched body (ShapeDef): where its particles start, and each
// site's integer cell on the body's lattice (what region clusters are cut from).
//   box:    sites at box.min + (i + 0.5) spacing, i in [0, n) per axis (the fluid block's lattice)
//   sphere: sites at center + i spacing with |i spacing| <= radius (i integer, any sign)
//   mesh:   the samples of the mesh's signed distance field (mesh_sdf.hpp) at voxel = spacing over
//           its box grown by half a spacing that lie inside the closed mesh (negative): the
//           inside test is the field's exact crossing count along x (winding number, or parity
//           for an inconsistently wound mesh), so a site's inside does not depend on the
//           distances. A mesh that is not closed is refused (SceneError naming its ".file").
// Order: z slowest, then y, then x (the box's order is for_each_lattice_site's).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "seiche/scene.hpp"

namespace seiche {

struct ClothMesh;

struct ShapeSites {
  std::vector<Vec3> position;                    ///< m
  std::vector<std::array<std::int32_t, 3>> cell;  ///< lattice cell of each site
  /// A mesh's: the size and FNV-1a 64 hash of the OBJ's bytes as read (input_fingerprint.hpp).
  std::uint64_t source_bytes = 0, source_fnv1a64 = 0;
  std::size_t size() const { return position.size(); }
};

/// The sites of a box or a sphere, or of a mesh (its loaded_sites, else voxelized from the file;
/// SceneError naming `json_path` + ".mesh.file" (file: the OBJ) for an unreadable or open mesh).
ShapeSites shape_sites(const ShapeDef& shape, const std::string& json_path);

/// How many particles the shape has (without building the sites of a box or a mesh).
std::size_t shape_site_count(const ShapeDef& shape);

/// The sites of a closed mesh at `spacing`. `file` and `mesh_path` (e.g. "shapes[0].mesh") name
/// the mesh in errors.
ShapeSites voxelize_mesh(const ClothMesh& mesh, float spacing, const std::string& file, const std::string& mesh_path);

/// Lattice samples of the mesh's box at `spacing` (the count voxelize_mesh visits): the bound
/// the reader checks before voxelizing.
double mesh_lattice_samples(const ClothMesh& mesh, float spacing);

}  // namespace seiche
