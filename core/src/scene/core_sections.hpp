// The sections every scene has, whatever its families: "solver", "domain" and "output".
#pragma once

#include "scene_section.hpp"

namespace seiche::detail {

SceneSection solver_section();
SceneSection domain_section();
SceneSection output_section();

}  // namespace seiche::detail
