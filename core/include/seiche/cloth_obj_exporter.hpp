// Cloth output: <name>.%04d.obj per cloth and frame (positions, vertex normals, the UVs of a
// generated sheet or of the input OBJ, and the faces as read), written atomically. Used by both
// `seiche run` and `seiche bake`.
#pragma once

#include <memory>

#include "seiche/frame_exporter.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// Null when the scene has no cloths. Reads the cloths' meshes (SceneError on bad input).
std::unique_ptr<FrameExporter> make_cloth_obj_exporter(const SceneDef& scene);

}  // namespace seiche
