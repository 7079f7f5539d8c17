// A cloth's triangle mesh: generated from a "sheet" or read from an OBJ file, checked, and its
// topology extracted for the constraints (edges for stretch, hinges for bending, the vertices
// that share a triangle for contact exclusion). Also the per-frame OBJ text of a cloth.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "seiche/scene.hpp"

namespace seiche {

struct ClothMesh {
  std::vector<Vec3> positions;  ///< rest positions in world space (m), one per vertex
  /// Triangles the simulation uses: the input's faces fanned into triangles, degenerate ones
  /// (a repeated vertex or an area below 1e-12 of the squared mean edge length) left out.
  std::vector<std::array<std::uint32_t, 3>> triangles;

  // For output, the faces as read: face f has corners [face_start[f], face_start[f + 1]).
  std::vector<std::uint32_t> face_start;         ///< size faces + 1
  std::vector<std::uint32_t> corner_vertex;      ///< per corner: vertex index
  std::vector<std::int32_t> corner_texcoord;     ///< per corner: index into texcoords, or -1
  std::vector<std::array<float, 2>> texcoords;   ///< "vt" (a sheet: one per vertex)

  std::vector<std::string> warnings;  ///< e.g. "3 degenerate triangles skipped (faces 4, 9, 12)"

  /// An OBJ mesh: the size and FNV-1a 64 hash of the bytes read_obj_mesh read, the input
  /// fingerprint a bake records (input_fingerprint.hpp). 0 and 0 for a generated sheet.
  std::uint64_t source_bytes = 0;
  std::uint64_t source_fnv1a64 = 0;

  std::size_t vertex_count() const { return positions.size(); }
};

/// A generated sheet (SheetDef's layout). `json_path` (e.g. "cloths[0].sheet") names the
/// definition in errors. Throws SceneError(file, json_path + ".resolution", ...) for a
/// resolution below 2 or above 4096, (file, json_path + ".size", ...) for a non-positive size and
/// (file, json_path + ".plane", ...) for a plane that is not two distinct axes. Triangles are
/// wound so that their normal points along the positive third axis (+y for "xz" and "zx").
ClothMesh make_sheet(const SheetDef& sheet, const std::string& file, const std::string& json_path);

/// Reads an OBJ file (only "v" and "f"; "vt" kept for output; normals, materials and groups are
/// ignored) and places it by scale and translate. Throws SceneError naming `obj_file`, with
/// json_path `json_path` + ".file", for a missing or unreadable file, malformed OBJ text, no
/// faces, a face index out of range, a non-finite coordinate. Degenerate faces are skipped with
/// a warning; a mesh whose every face is degenerate is an error.
ClothMesh read_obj_mesh(const std::filesystem::path& obj_file, const ClothMeshDef& def,
                        const std::string& json_path);

/// Topology of a mesh's simulated triangles.
struct ClothTopology {
  /// Unique undirected edges, (min, max) vertex pairs, sorted.
  std::vector<std::array<std::uint32_t, 2>> edges;
  /// Interior edges shared by exactly two triangles, as hinges (a, b, c, d): triangle (a, b, c)
  /// and triangle (b, a, d), with (a, b, c) in the vertex order of the first triangle; sorted
  /// by (min(a, b), max(a, b)).
  std::vector<std::array<std::uint32_t, 4>> hinges;
  /// Area (m^2) a vertex owns: a third of the area of each triangle it belongs to.
  std::vector<double> vertex_area;
  /// Vertices sharing a triangle with vertex v (v itself excluded), sorted:
  /// [adjacent_start[v], adjacent_start[v + 1]).
  std::vector<std::uint32_t> adjacent_start, adjacent;
};

/// Throws SceneError(file, json_path, ...) for a non-manifold edge (shared by more than two
/// triangles), naming its two vertices and the number of triangles.
ClothTopology build_topology(const ClothMesh& mesh, const std::string& file,
                             const std::string& json_path);

/// Wavefront OBJ text of a cloth at the given positions (vertex order of the mesh): "v" lines,
/// one area-weighted vertex normal "vn" per vertex (a guarded normalization: (0, 1, 0) where
/// the normal vanishes), the mesh's "vt", and the faces as read, as "f v/vt/vn" corners (1-based;
/// "v//vn" without texcoords). Floats printed as the shortest text that reads back to the same
/// float (at most 9 significant digits).
std::string encode_cloth_obj(const ClothMesh& mesh, std::span<const Vec3> positions);

}  // namespace seiche
