// The scene's "particles" (ParticleDef) and "distance_constraints" (DistanceConstraintDef)
// sections: raw particles and the distance constraints between them.
#pragma once

#include "scene/scene_section.hpp"

namespace seiche::detail {

SceneSection particles_section();
SceneSection distance_constraints_section();

}  // namespace seiche::detail
