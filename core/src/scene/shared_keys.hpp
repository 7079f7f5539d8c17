// Pieces several sections share: the "box" object (fluid blocks, pin boxes, box colliders), the
// placement of an OBJ mesh (cloth and collider meshes) and the helpers of the checks across
// sections (a point inside the domain, a mesh file that exists).
#pragma once

#include <string>

#include "key_table.hpp"

namespace seiche::detail {

constexpr char kAxis[3] = {'x', 'y', 'z'};

const KeyTable<BoxDef>& box_keys();
/// A box: min and max, min <= max on every axis.
BoxDef read_box(JsonReader r);

const KeyTable<ClothMeshDef>& mesh_placement_keys();
/// "file" (required, not empty), "translate", "scale".
ClothMeshDef read_mesh_placement(JsonReader r);

std::string format_vec(const Vec3& v);  ///< "[1, 2, 3]"
bool inside(const Vec3& p, const DomainDef& d);
/// "[min]..[max]" of the domain, for messages.
std::string format_domain(const DomainDef& d);

/// A relative mesh path resolved against the scene file's folder.
std::string resolve_mesh_path(const std::string& file, const std::string& base_dir);
/// A mesh file that is not there is the scene's error (it names the file); what is wrong inside
/// an OBJ is reported by the OBJ reader, naming the OBJ.
void check_mesh_file(const std::string& mesh_file, const std::string& file, const std::string& path);

}  // namespace seiche::detail
