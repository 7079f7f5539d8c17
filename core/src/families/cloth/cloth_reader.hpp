// The scene's "cloths" section (ClothDef, SheetDef, a mesh's ClothMeshDef): its key tables,
// reader and checks.
#pragma once

#include "scene/scene_section.hpp"

namespace seiche::detail {

SceneSection cloths_section();

}  // namespace seiche::detail
