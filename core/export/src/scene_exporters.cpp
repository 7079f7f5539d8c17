#include "seiche/export/scene_exporters.hpp"

#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "seiche/scene_loader.hpp"
#ifdef SEICHE_HAS_OPENVDB
#include "seiche/export/vdb_exporter.hpp"
#endif

namespace seiche {

std::vector<std::unique_ptr<FrameExporter>> scene_exporters(const SceneDef& scene, const std::string& source,
                                                            bool resuming, std::ostream* warnings) {
  std::vector<std::unique_ptr<FrameExporter>> exporters = family_exporters(scene);
  const OutputDef& o = scene.output;
  if (!o.any_vdb() && !o.mesh) return exporters;
  std::vector<std::string> asked;
  for (auto [on, grid] : {std::pair{o.vdb_surface, "surface"}, {o.vdb_density, "density"}, {o.vdb_points, "points"},
                          {o.vdb_velocity, "v"}})
    if (on) asked.push_back(grid);
  const std::string what = fmt::format("{}{}{}", asked.empty() ? "" : fmt::format("output.vdb = [{}]", fmt::join(asked, ", ")),
                                       !asked.empty() && o.mesh ? " and " : "", o.mesh ? "output.mesh = true" : "");
  if (scene.fluids.empty()) {
    if (!scene.cloths.empty()) return exporters;  // the fluid's output keys do not concern cloths
    if (warnings)
      *warnings << fmt::format("seiche: warning: the scene asks for {} but has no fluid: writing particles only\n", what);
    return exporters;
  }
#ifdef SEICHE_HAS_OPENVDB
  try {
    if (auto e = make_vdb_exporter(scene)) exporters.push_back(std::move(e));
  } catch (const SceneError& e) {  // the exporter knows the scene, not its file
    throw SceneError(source, e.json_path(), e.problem());
  }
#else
  (void)source;
  throw ExportUnavailableError(fmt::format(
      "the scene asks for {}, but this seiche was built without OpenVDB: rebuild with -DSEICHE_WITH_OPENVDB=ON{}",
      what, resuming ? "" : ", or bake particles only with --set output.vdb=[] --set output.mesh=false"));
#endif
  (void)resuming;
  return exporters;
}

}  // namespace seiche
