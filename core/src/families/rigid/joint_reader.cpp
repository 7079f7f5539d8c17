// The "joints" section: the key table of a joint, its reader, and the rules across keys and
// sections (the bodies it names exist, a hinge's axis is not zero, limits and motors only on
// hinges, a lower limit not above the upper).
#include <fmt/format.h>

#include <cmath>

#include "rigid_reader.hpp"
#include "scene/output_name.hpp"
#include "scene/shared_keys.hpp"

namespace seiche::detail {

namespace {

const KeyTable<JointDef>& joint_keys() {
  using K = Key<JointDef>;
  static const KeyTable<JointDef> keys{
      K("type", &JointDef::type)
          .choices({"ball", "hinge", "fixed"})
          .doc("ball: the anchor points meet; hinge: they meet and the axes stay aligned; fixed: they meet and "
               "the relative orientation stays"),
      K("body_a", &JointDef::body_a)
          .valid_note("a name in `rigid_bodies`, or `world`")
          .doc("the first body, or the world (a fixed frame)"),
      K("body_b", &JointDef::body_b)
          .required()
          .valid_note("a name in `rigid_bodies`, not `body_a`")
          .doc("the second body"),
      K("anchor", &JointDef::anchor)
          .required()
          .unit("m")
          .doc("the connector point, world frame at the start: each body keeps it in its own frame"),
      K("axis", &JointDef::axis)
          .valid_note("not zero; hinge only")
          .doc("hinge: its axis, world frame at the start"),
      K("limits", &JointDef::limits, Range::closed(-180, 180))
          .unit("degrees")
          .default_text("none")
          .valid_note("lower ≤ upper; hinge only")
          .doc("hinge: the range of body_b's angle about the axis relative to body_a, from the start"),
      K("target_angle", &JointDef::target_angle)
          .unit("degrees")
          .default_text("none")
          .valid_note("hinge only; not with `target_velocity`")
          .doc("hinge motor: drives the hinge angle (from the start) to this angle"),
      K("target_velocity", &JointDef::target_velocity)
          .unit("degrees/s")
          .default_text("none")
          .valid_note("hinge only; not with `target_angle`")
          .doc("hinge motor: turns body_b about the axis relative to body_a at this rate"),
      K("compliance", &JointDef::compliance, Range::at_least(0))
          .unit("m/N, rad/(N m)")
          .doc("inverse stiffness of the joint's positional and angular constraints (XPBD); 0 = rigid"),
      K("motor_compliance", &JointDef::motor_compliance, Range::at_least(0))
          .unit("rad/(N m)")
          .doc("inverse stiffness of the motor's drive; 0 = rigid"),
  };
  return keys;
}

void read_joint(JsonReader r, SceneDef& scene) {
  JointDef j;
  read_keys(r, joint_keys(), j);
  j.has_limits = r.has("limits");
  j.has_target_angle = r.has("target_angle");
  j.has_target_velocity = r.has("target_velocity");
  const bool hinge = j.type == "hinge";
  for (const char* key : {"axis", "limits", "target_angle", "target_velocity", "motor_compliance"})
    if (!hinge && r.has(key)) r.fail_at(key, fmt::format("a {} joint has no \"{}\" (only a hinge has)", j.type, key));
  if (hinge && !(std::hypot(double(j.axis[0]), double(j.axis[1]), double(j.axis[2])) > 0.0))
    r.fail_at("axis", fmt::format("{} has no direction: a hinge's axis must not be zero", format_vec(j.axis)));
  if (j.has_limits && j.limits[0] > j.limits[1])
    r.fail_at("limits", fmt::format("the lower limit {} is above the upper limit {}", j.limits[0], j.limits[1]));
  if (j.has_target_angle && j.has_target_velocity)
    r.fail_at("target_velocity", "a motor drives to a target angle or at a target velocity, not both");
  r.finish();
  scene.joints.push_back(j);
}

void check_joints(SceneDef& scene, const std::string& file) {
  const auto exists = [&](const std::string& name) {
    for (const RigidBodyDef& b : scene.rigid_bodies)
      if (b.name == name) return true;
    return false;
  };
  for (std::size_t k = 0; k < scene.joints.size(); ++k) {
    const JointDef& j = scene.joints[k];
    const std::string path = element_path("joints", k);
    if (j.body_a != "world" && !exists(j.body_a))
      fail(file, path + ".body_a", fmt::format("names no body: \"{}\" is not in rigid_bodies (nor \"world\")", j.body_a));
    if (!exists(j.body_b))
      fail(file, path + ".body_b", fmt::format("names no body: \"{}\" is not in rigid_bodies", j.body_b));
    if (j.body_a == j.body_b)
      fail(file, path + ".body_b", fmt::format("\"{}\" is also body_a: a joint holds two bodies", j.body_b));
  }
}

}  // namespace

SceneSection joints_section() {
  return {"joints", true, "joints between rigid bodies, or a body and the world (ball, hinge, fixed)", read_joint,
          check_joints, [] { return std::vector<KeyTableDoc>{{"joints", key_docs(joint_keys())}}; }};
}

}  // namespace seiche::detail
