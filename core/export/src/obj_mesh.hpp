// The fluid surface as a Wavefront OBJ mesh: OpenVDB's volumeToMesh on the level set's zero
// crossing (one vertex per boundary voxel, quads between them, no adaptivity), with per-vertex
// normals from the level set's gradient (smooth shading in any renderer). Faces are written as
// "f v//vn ..." with 1-based indices, counter-clockwise seen from outside.
#pragma once

#include <openvdb/openvdb.h>

#include <string>
#include <string_view>

namespace seiche::exporting {

/// The OBJ text of `surface`'s zero isosurface, headed by a comment line `header` ("# " added).
/// An empty level set gives an OBJ with only the comment.
std::string encode_obj_mesh(const openvdb::FloatGrid& surface, std::string_view header);

}  // namespace seiche::exporting
