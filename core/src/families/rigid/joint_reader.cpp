// The "joints" section: the key table of a joint, its reader, and the rules across keys and
// sections (the bodies it names exist, a hinge's, slider's or universal joint's axis is not zero
// and a universal joint's two axes are perpendicular, each type's keys only on that type, every
// range's lower end not above its upper, a motor has one target).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rigid_reader.hpp"
#include "scene/output_name.hpp"
#include "scene/shared_keys.hpp"

namespace seiche::detail {

namespace {

// A universal joint's axes may be this far from perpendicular: cos(90 - 0.01 degrees).
constexpr double kPerpendicularCosine = 1.7453292e-4;

const KeyTable<JointDef>& joint_keys() {
  using K = Key<JointDef>;
  static const KeyTable<JointDef> keys{
      K("type", &JointDef::type)
          .choices({"ball", "hinge", "fixed", "distance", "slider", "universal"})
          .doc("ball: the anchor points meet; hinge: they meet and the axes stay aligned; fixed: they meet and "
               "the relative orientation stays; distance: the anchor points stay within a range of distances; "
               "slider: the relative orientation stays and body_b's anchor moves only along the axis; universal: they meet "
               "and body_a's axis stays perpendicular to body_b's (a Cardan joint)"),
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
          .doc("the connector point, world frame at the start: each body keeps it in its own frame (a distance "
               "joint: body_a's point)"),
      K("anchor_b", &JointDef::anchor_b)
          .unit("m")
          .default_text("`anchor`")
          .valid_note("distance only")
          .doc("distance: body_b's point, world frame at the start"),
      K("axis", &JointDef::axis)
          .valid_note("not zero; hinge, slider and universal only")
          .doc("hinge, slider: the axis, world frame at the start (body_a keeps it in its frame); universal: "
               "body_a's axis"),
      K("axis_b", &JointDef::axis_b)
          .default_text("required for universal")
          .valid_note("not zero, perpendicular to `axis` within 0.01°; universal only")
          .doc("universal: body_b's axis, world frame at the start (body_b keeps it in its frame)"),
      K("limits", &JointDef::limits, Range::closed(-180, 180))
          .unit("degrees")
          .default_text("none")
          .valid_note("lower ≤ upper; hinge only")
          .doc("hinge: the range of body_b's angle about the axis relative to body_a, from the start"),
      K("distance", &JointDef::distance, Range::at_least(0))
          .unit("m")
          .default_text("the distance at the start, both ways")
          .valid_note("min ≤ max; distance only")
          .doc("distance: the range [min, max] of the distance between the two points (a rope: `[0, length]`)"),
      K("travel", &JointDef::travel)
          .unit("m")
          .default_text("free")
          .valid_note("lower ≤ upper; slider only")
          .doc("slider: the range of body_b's anchor along the axis, from where it starts"),
      K("target_angle", &JointDef::target_angle)
          .unit("degrees")
          .default_text("none")
          .valid_note("hinge only; not with `target_velocity`")
          .doc("hinge motor: drives the hinge angle (from the start) to this angle"),
      K("target_velocity", &JointDef::target_velocity)
          .unit("degrees/s, m/s")
          .default_text("none")
          .valid_note("hinge or slider; not with `target_angle` or `target_position`")
          .doc("hinge motor: turns body_b about the axis relative to body_a at this rate (degrees/s); slider "
               "motor: moves body_b's anchor along the axis at this rate (m/s)"),
      K("target_position", &JointDef::target_position)
          .unit("m")
          .default_text("none")
          .valid_note("slider only; not with `target_velocity`")
          .doc("slider motor: drives body_b's anchor to this position along the axis (from the start)"),
      K("compliance", &JointDef::compliance, Range::at_least(0))
          .unit("m/N, rad/(N m)")
          .doc("inverse stiffness of the joint's positional and angular constraints (XPBD); 0 = rigid"),
      K("motor_compliance", &JointDef::motor_compliance, Range::at_least(0))
          .unit("rad/(N m), m/N")
          .valid_note("hinge or slider, with a target")
          .doc("inverse stiffness of the motor's drive (a hinge's in rad/(N m), a slider's in m/N); 0 = rigid"),
  };
  return keys;
}

void read_joint(JsonReader r, SceneDef& scene) {
  JointDef j;
  read_keys(r, joint_keys(), j);
  j.has_anchor_b = r.has("anchor_b");
  j.has_limits = r.has("limits");
  j.has_distance = r.has("distance");
  j.has_travel = r.has("travel");
  j.has_target_angle = r.has("target_angle");
  j.has_target_velocity = r.has("target_velocity");
  j.has_target_position = r.has("target_position");
  // Each type's own keys: another type's key is an error, not silently ignored.
  struct Owned {
    const char* key;
    const char* types;  // as the message says it
    bool (*owns)(const std::string& type);
  };
  static constexpr Owned kOwned[] = {
      {"anchor_b", "a distance joint", [](const std::string& t) { return t == "distance"; }},
      {"axis", "a hinge, a slider or a universal joint",
       [](const std::string& t) { return t == "hinge" || t == "slider" || t == "universal"; }},
      {"axis_b", "a universal joint", [](const std::string& t) { return t == "universal"; }},
      {"limits", "a hinge", [](const std::string& t) { return t == "hinge"; }},
      {"target_angle", "a hinge", [](const std::string& t) { return t == "hinge"; }},
      {"target_velocity", "a hinge or a slider", [](const std::string& t) { return t == "hinge" || t == "slider"; }},
      {"target_position", "a slider", [](const std::string& t) { return t == "slider"; }},
      {"motor_compliance", "a hinge or a slider", [](const std::string& t) { return t == "hinge" || t == "slider"; }},
      {"distance", "a distance joint", [](const std::string& t) { return t == "distance"; }},
      {"travel", "a slider", [](const std::string& t) { return t == "slider"; }},
  };
  for (const Owned& o : kOwned)
    if (!o.owns(j.type) && r.has(o.key))
      r.fail_at(o.key, fmt::format("a {} joint has no \"{}\" (only {} has)", j.type, o.key, o.types));
  const auto norm = [](const Vec3& v) { return std::hypot(double(v[0]), double(v[1]), double(v[2])); };
  if ((j.type == "hinge" || j.type == "slider" || j.type == "universal") && !(norm(j.axis) > 0.0))
    r.fail_at("axis", fmt::format("{} has no direction: a {}'s axis must not be zero", format_vec(j.axis), j.type));
  if (j.type == "universal") {
    if (!r.has("axis_b")) r.fail_at("axis_b", "required key is missing: a universal joint needs body_b's axis");
    if (!(norm(j.axis_b) > 0.0))
      r.fail_at("axis_b", fmt::format("{} has no direction: a universal joint's axis_b must not be zero",
                                      format_vec(j.axis_b)));
    const double cosine = (double(j.axis[0]) * j.axis_b[0] + double(j.axis[1]) * j.axis_b[1] +
                           double(j.axis[2]) * j.axis_b[2]) / (norm(j.axis) * norm(j.axis_b));
    if (!(std::fabs(cosine) <= kPerpendicularCosine))
      r.fail_at("axis_b", fmt::format("{} is at {:.4g} degrees to axis {}: a universal joint's axes must be "
                                      "perpendicular at the start (within 0.01 degree)",
                                      format_vec(j.axis_b), std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / std::numbers::pi,
                                      format_vec(j.axis)));
  }
  const auto ordered = [&](const char* key, bool given, const std::array<float, 2>& range, const char* what) {
    if (given && range[0] > range[1])
      r.fail_at(key, fmt::format("the lower {} {} is above the upper {} {}", what, range[0], what, range[1]));
  };
  ordered("limits", j.has_limits, j.limits, "limit");
  ordered("distance", j.has_distance, j.distance, "distance");
  ordered("travel", j.has_travel, j.travel, "travel");
  if (j.has_target_angle && j.has_target_velocity)
    r.fail_at("target_velocity", "a motor drives to a target angle or at a target velocity, not both");
  if (j.has_target_position && j.has_target_velocity)
    r.fail_at("target_velocity", "a motor drives to a target position or at a target velocity, not both");
  if (r.has("motor_compliance") && !j.has_target_angle && !j.has_target_velocity && !j.has_target_position)
    r.fail_at("motor_compliance", fmt::format("a motor without a target: give the {} a {} or a target_velocity",
                                              j.type, j.type == "slider" ? "target_position" : "target_angle"));
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
  return {"joints", true, "joints between rigid bodies, or a body and the world (ball, hinge, fixed, distance, slider, universal)",
          read_joint,
          check_joints, [] { return std::vector<KeyTableDoc>{{"joints", key_docs(joint_keys())}}; }};
}

}  // namespace seiche::detail
