// The scene's "colliders" section (ColliderDef): its key tables, reader and checks.
#pragma once

#include "scene/scene_section.hpp"

namespace seiche::detail {

SceneSection colliders_section();

}  // namespace seiche::detail
