// The reader registry: one row per section of a scene ("solver", "fluids", "cloths", ...) with
// the function that reads it, the checks across sections it needs once every section is read,
// and its key tables for docs/scene-format.md. Each family's row, reader and key tables live in
// its folder (core/src/families/<family>/<family>_reader.cpp); a new family adds its reader file
// and one row to scene_sections() (section_registry.cpp).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "json_reader.hpp"
#include "key_table.hpp"

namespace seiche::detail {

struct SceneSection {
  std::string_view key;  ///< the key in the scene's root object
  bool is_array;         ///< an array of entries ("fluids") or one object ("solver")
  std::string_view doc;  ///< the root table's line of documentation
  /// Reads one entry (or the section's object) into the scene.
  void (*read)(JsonReader entry, SceneDef& scene);
  /// Rules across sections (a box inside the domain, an index within "particles"), run in
  /// registry order once every section is read; may complete the definitions (absolute mesh
  /// paths, meshes read once). Null when there are none.
  void (*check)(SceneDef& scene, const std::string& file);
  /// The section's key tables, each rendered between its markers in docs/scene-format.md.
  std::vector<KeyTableDoc> (*docs)();
};

/// Every section, in reading order.
const std::vector<SceneSection>& scene_sections();

/// The root key table ("name" and one row per section) and every section's tables: all the key
/// tables of docs/scene-format.md.
std::vector<KeyTableDoc> scene_key_tables();

/// Reads the root object of a scene: "name", then every section in registry order; rejects
/// unknown keys, then runs every section's checks.
void read_scene_sections(JsonReader root, SceneDef& scene);

}  // namespace seiche::detail
