// Rigid body output: bodies.%04d.jsonl per frame, one JSON object a line per body in scene
// order: {"name": ..., "position": [x, y, z], "orientation": [w, x, y, z], "velocity": [...],
// "angular_velocity": [...]} (m, unit quaternion body to world, m/s, rad/s; world frame),
// written atomically like every frame file; and with output.body_meshes (the default) every
// body's surface in the world as <body name>.%04d.obj (body_surface.hpp: a mesh body's own
// triangles, a generated mesh for a box, sphere or capsule). Used by both `seiche run` and
// `seiche bake`.
#pragma once

#include <memory>

#include "seiche/frame_exporter.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// Null when the scene has no rigid bodies.
std::unique_ptr<FrameExporter> make_body_exporter(const SceneDef& scene);

/// One frame's bodies.%04d.jsonl: a line per body of `scene`, from `bodies` (scene order).
std::string encode_bodies_jsonl(const SceneDef& scene, std::span<const BodyPose> bodies);

}  // namespace seiche
