// The "box" object, the placement of an OBJ mesh and the helpers of the checks across sections.
#include "shared_keys.hpp"

#include <filesystem>
#include <system_error>

#include <fmt/format.h>

namespace seiche::detail {

const KeyTable<BoxDef>& box_keys() {
  static const KeyTable<BoxDef> keys{
      Key<BoxDef>("min", &BoxDef::min).unit("m").valid_note("≤ `max` on every axis").doc("lower corner"),
      Key<BoxDef>("max", &BoxDef::max).unit("m").valid_note("≥ `min` on every axis").doc("upper corner"),
  };
  return keys;
}

BoxDef read_box(JsonReader r) {
  BoxDef b = read_object(r, box_keys());
  for (int a = 0; a < 3; ++a) {
    if (b.min[a] > b.max[a])
      r.fail_here(fmt::format("min > max along {} ({} > {})", kAxis[a], b.min[a], b.max[a]));
  }
  return b;
}

const KeyTable<ClothMeshDef>& mesh_placement_keys() {
  static const KeyTable<ClothMeshDef> keys{
      Key<ClothMeshDef>("file", &ClothMeshDef::file)
          .required()
          .valid_note("an OBJ file")
          .doc("relative paths are relative to the scene file's folder"),
      Key<ClothMeshDef>("translate", &ClothMeshDef::translate)
          .unit("m")
          .doc("x_world = x_file · scale + translate"),
      Key<ClothMeshDef>("scale", &ClothMeshDef::scale, Range::above(0)).doc("the factor of x_file"),
  };
  return keys;
}

ClothMeshDef read_mesh_placement(JsonReader r) {
  ClothMeshDef m = read_object(r, mesh_placement_keys());
  if (m.file.empty()) r.fail_at("file", "must not be empty");
  return m;
}

std::string format_vec(const Vec3& v) { return fmt::format("[{}, {}, {}]", v[0], v[1], v[2]); }

bool inside(const Vec3& p, const DomainDef& d) {
  for (int a = 0; a < 3; ++a)
    if (p[a] < d.min[a] || p[a] > d.max[a]) return false;
  return true;
}

std::string format_domain(const DomainDef& d) { return fmt::format("{}..{}", format_vec(d.min), format_vec(d.max)); }

std::string resolve_mesh_path(const std::string& file, const std::string& base_dir) {
  const std::filesystem::path p(file);
  if (p.is_absolute() || base_dir.empty()) return file;
  return (std::filesystem::path(base_dir) / p).lexically_normal().string();
}

void check_mesh_file(const std::string& mesh_file, const std::string& file, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(mesh_file, ec))
    fail(file, path, fmt::format("cannot open the mesh {}: {}", mesh_file,
                                 std::filesystem::exists(mesh_file, ec) ? "not a regular file" : "no such file"));
}

}  // namespace seiche::detail
