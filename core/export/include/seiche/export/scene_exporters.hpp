// Every frame exporter a scene's bake runs besides the particle PLY it writes itself: the
// families' (each cloth's OBJ, frame_exporter.hpp) and the fluid's .vdb and .obj surface that
// the output section asks for (vdb_exporter.hpp). What `seiche bake` and the Python API's
// seiche.bake() hand to bake_scene (bake.hpp).
//
// A build without OpenVDB (-DSEICHE_WITH_OPENVDB=OFF) has this function too: it then refuses a
// scene whose output asks for .vdb or .obj files (ExportUnavailableError, bad input), naming the
// keys to change.
#pragma once

#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "seiche/frame_exporter.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// The scene asks for output this build cannot write (.vdb or .obj without OpenVDB). Bad input:
/// what() says which keys ask for it and how to rebuild or change them.
class ExportUnavailableError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The exporters of `scene`: the families' first, then the fluid's. `source` is the file the scene
/// came from (the scene file, or bake.json on a resume): SceneErrors of the fluid exporter name it.
/// `resuming`: a resume's refusal does not suggest --set (the overrides are the recorded ones).
/// `warnings` (may be null) gets a line when the scene asks for fluid output but has no fluid.
std::vector<std::unique_ptr<FrameExporter>> scene_exporters(const SceneDef& scene, const std::string& source,
                                                            bool resuming, std::ostream* warnings);

}  // namespace seiche
