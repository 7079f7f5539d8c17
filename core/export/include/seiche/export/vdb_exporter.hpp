// The OpenVDB export of fluid frames: <name>.%04d.vdb (grids "surface", "density", "points",
// "v" as the scene's output section asks) and <name>.%04d.obj (the surface as a mesh).
#pragma once

#include <memory>

#include "seiche/frame_exporter.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// The exporter for what scene.output asks for; null when it asks for no .vdb and no mesh, or
/// when the scene has no fluid.
std::unique_ptr<FrameExporter> make_vdb_exporter(const SceneDef& scene);

}  // namespace seiche
