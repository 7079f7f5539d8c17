// The reader registry (one row per scene section, in reading order) and the reading of the
// scene's root object through it.
#include "scene_section.hpp"

#include <fmt/format.h>

#include "core_sections.hpp"
#include "families/cloth/cloth_reader.hpp"
#include "families/collider/collider_reader.hpp"
#include "families/distance/distance_reader.hpp"
#include "families/fluid/fluid_reader.hpp"
#include "families/rigid/rigid_reader.hpp"
#include "families/shape/shape_reader.hpp"
#include "output_name.hpp"

namespace seiche::detail {

const std::vector<SceneSection>& scene_sections() {
  static const std::vector<SceneSection> sections{
      solver_section(),
      domain_section(),
      output_section(),
      fluids_section(),
      particles_section(),
      distance_constraints_section(),
      colliders_section(),
      cloths_section(),
      shapes_section(),
      rigid_bodies_section(),
      joints_section(),
  };
  return sections;
}

namespace {

const KeyTable<SceneDef>& root_keys() {
  static const KeyTable<SceneDef> keys{
      Key<SceneDef>("name", &SceneDef::name)
          .default_text("the file's stem (`scenes/pool.json` → `pool`); `scene` for a scene given as text "
                        "(e.g. the built-in one, which sets its name)")
          .valid_note(kOutputNameRule)
          .doc("the scene's name: the stem of the fluid's output files and of the default output folder "
               "`out/<name>`"),
  };
  return keys;
}

}  // namespace

std::vector<KeyTableDoc> scene_key_tables() {
  KeyTableDoc root{"root", key_docs(root_keys())};
  std::vector<KeyTableDoc> tables;
  for (const SceneSection& s : scene_sections()) {
    root.rows.push_back({code_span(s.key), s.is_array ? "array of objects" : "object", "–",
                         s.is_array ? "`[]`" : "all defaults", "see below", std::string(s.doc)});
    for (KeyTableDoc& t : s.docs()) tables.push_back(std::move(t));
  }
  tables.insert(tables.begin(), std::move(root));
  return tables;
}

void read_scene_sections(JsonReader root, SceneDef& scene) {
  read_keys(root, root_keys(), scene);
  if (const std::string problem = output_name_problem(scene.name); !problem.empty())
    root.fail_at("name", root.has("name") ? problem
                                          : fmt::format("the scene has no \"name\", and its default, the file's "
                                                        "stem, {}; set \"name\" in the scene or --set name=...",
                                                        problem));
  for (const SceneSection& s : scene_sections()) {
    if (s.is_array) {
      for (const JsonReader& entry : root.objects(s.key)) s.read(entry, scene);
    } else if (auto object = root.optional_object(s.key)) {
      s.read(*object, scene);
    }
  }
  root.finish();
  const std::string file = root.file();
  for (const SceneSection& s : scene_sections())
    if (s.check) s.check(scene, file);
}

}  // namespace seiche::detail
