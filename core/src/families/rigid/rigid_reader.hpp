// The scene's "rigid_bodies" (RigidBodyDef) and "joints" (JointDef) sections: their key
// tables, readers and checks (rigid_body_reader.cpp, joint_reader.cpp).
#pragma once

#include "scene/scene_section.hpp"

namespace seiche::detail {

SceneSection rigid_bodies_section();
SceneSection joints_section();

}  // namespace seiche::detail
