// The scene's "shapes" section (ShapeDef): its key table, reader and checks.
#pragma once

#include "scene/scene_section.hpp"

namespace seiche::detail {

SceneSection shapes_section();

}  // namespace seiche::detail
