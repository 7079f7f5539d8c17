// The scene's "fluids" section (FluidDef): its key table, reader and checks.
#pragma once

#include "scene/scene_section.hpp"

namespace seiche::detail {

SceneSection fluids_section();

}  // namespace seiche::detail
