#include "rigid_family.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "body_shape.hpp"

namespace seiche {

using rigid::Joint;
using rigid::JointType;
using rigid::MotorMode;
using rigid::Quatd;
using rigid::RigidBody;
using rigid::Vec3d;

namespace {

constexpr const char* kBodiesChunk = "rigid.bodies";  // the checkpoint chunk of the bodies' state
constexpr const char* kTreesChunk = "rigid.joint_trees";  // the tree solve's multipliers

// One body's state as it goes into the checkpoint.
struct SavedBody {
  Vec3d x;
  Quatd q;
  Vec3d v;
  Vec3d omega;
};

Vec3d to_d(const Vec3& v) { return {double(v[0]), double(v[1]), double(v[2])}; }
constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;

int body_index(const SceneDef& scene, const std::string& name) {
  for (std::size_t k = 0; k < scene.rigid_bodies.size(); ++k)
    if (scene.rigid_bodies[k].name == name) return int(k);
  return -1;  // "world" (the reader has checked every other name)
}

JointType joint_type_of(const std::string& type) {
  if (type == "hinge") return JointType::Hinge;
  if (type == "fixed") return JointType::Fixed;
  if (type == "distance") return JointType::Distance;
  if (type == "slider") return JointType::Slider;
  if (type == "universal") return JointType::Universal;
  return JointType::Ball;
}

// A unit vector perpendicular to unit u.
Vec3d perpendicular(Vec3d u) {
  const Vec3d other = std::fabs(u.x) < 0.6 ? Vec3d{1.0, 0.0, 0.0} : Vec3d{0.0, 1.0, 0.0};
  return rigid::normalized_or_zero(cross(u, other));
}

std::vector<RigidBody> make_bodies(const SceneDef& scene, std::vector<double>& extent) {
  std::vector<RigidBody> bodies;
  for (const RigidBodyDef& d : scene.rigid_bodies) {
    const rigid::MassProperties m = rigid::mass_properties(rigid::body_shape_def(d));
    // The turn from the rest pose, after the body frame's own turn from the shape's rest axes.
    const Quatd q = rigid::rotation_quaternion(double(d.angle) * kRadiansPerDegree *
                                               rigid::normalized_or_zero(to_d(d.axis))) *
                    m.principal;
    bodies.push_back(rigid::make_body(to_d(d.position), q, to_d(d.velocity), to_d(d.angular_velocity), m.mass,
                                      m.inertia, d.fixed));
    extent.push_back(m.extent);
  }
  return bodies;
}

std::vector<Joint> make_joints(const SceneDef& scene, const std::vector<RigidBody>& bodies,
                               const std::vector<double>& extent) {
  const RigidBody world;
  std::vector<Joint> joints;
  for (const JointDef& d : scene.joints) {
    Joint j;
    j.type = joint_type_of(d.type);
    j.body_a = body_index(scene, d.body_a);
    j.body_b = body_index(scene, d.body_b);
    const RigidBody& a = j.body_a < 0 ? world : bodies[std::size_t(j.body_a)];
    const RigidBody& b = j.body_b < 0 ? world : bodies[std::size_t(j.body_b)];
    const Vec3d anchor = to_d(d.anchor);
    const Vec3d anchor_b = d.has_anchor_b ? to_d(d.anchor_b) : anchor;
    j.anchor_a = rotate_back(a.q, anchor - a.x);
    j.anchor_b = rotate_back(b.q, anchor_b - b.x);
    const Vec3d axis = rigid::normalized_or_zero(to_d(d.axis));
    const Vec3d normal = perpendicular(axis);
    j.axis_a = rotate_back(a.q, axis), j.axis_b = rotate_back(b.q, axis);
    j.normal_a = rotate_back(a.q, normal), j.normal_b = rotate_back(b.q, normal);
    if (j.type == JointType::Universal) {
      // Body b's axis made exactly perpendicular to a's (the reader allows 0.01 degree off).
      const Vec3d given_b = rigid::normalized_or_zero(to_d(d.axis_b));
      const Vec3d axis_b = rigid::normalized_or_zero(given_b - dot(given_b, axis) * axis);
      j.axis_b = rotate_back(b.q, axis_b);
    }
    j.rest_rotation = conjugate(a.q) * b.q;
    j.compliance = d.compliance;
    if (j.type == JointType::Hinge) {
      j.limited = d.has_limits;
      j.lower = d.limits[0] * kRadiansPerDegree, j.upper = d.limits[1] * kRadiansPerDegree;
    } else if (j.type == JointType::Slider) {
      j.limited = d.has_travel;
      j.lower = d.travel[0], j.upper = d.travel[1];
    }
    const double start_distance = length(anchor_b - anchor);
    j.min_distance = d.has_distance ? d.distance[0] : start_distance;
    j.max_distance = d.has_distance ? d.distance[1] : start_distance;
    if (d.has_target_angle) j.motor = MotorMode::Position, j.target = d.target_angle * kRadiansPerDegree;
    if (d.has_target_position) j.motor = MotorMode::Position, j.target = d.target_position;
    if (d.has_target_velocity)  // a slider's in m/s, a hinge's in degrees/s
      j.motor = MotorMode::Velocity,
      j.target = j.type == JointType::Slider ? double(d.target_velocity) : d.target_velocity * kRadiansPerDegree;
    j.motor_compliance = d.motor_compliance;
    // The joint's length: how far its bodies reach from the anchor (at least a body's size, and
    // a distance joint's longest distance).
    double reach = j.type == JointType::Distance ? j.max_distance : 0.0;
    for (int k : {j.body_a, j.body_b})
      if (k >= 0) reach = std::max({reach, length(bodies[std::size_t(k)].x - anchor), extent[std::size_t(k)]});
    j.length = reach > 0.0 ? reach : 1.0;
    joints.push_back(j);
  }
  return joints;
}

// The pairs of bodies that do not touch each other: those a joint joins, and any two of one
// articulation (bodies linked through joints between movable bodies: a chain, a ragdoll), as
// Bullet's multibodies leave out self-collision by default. Bodies that share a pivot (a ragdoll's
// arms on its shoulder) sweep into each other at it with any turn, and a contact there fights the
// joints; a fixed body, like the world, links nothing (pendulums hung from one fixed bar collide).
std::vector<std::pair<int, int>> contactless_pairs(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies) {
  // Union-find of the articulations.
  std::vector<int> root(bodies.size());
  for (std::size_t k = 0; k < root.size(); ++k) root[k] = int(k);
  const auto find = [&](int k) {
    while (root[std::size_t(k)] != k) k = root[std::size_t(k)] = root[std::size_t(root[std::size_t(k)])];
    return k;
  };
  std::vector<std::pair<int, int>> pairs;
  for (const Joint& j : joints) {
    pairs.push_back({j.body_a, j.body_b});
    if (j.body_a < 0 || j.body_b < 0 || bodies[std::size_t(j.body_a)].fixed() || bodies[std::size_t(j.body_b)].fixed())
      continue;
    root[std::size_t(find(j.body_a))] = find(j.body_b);
  }
  for (std::size_t a = 0; a < bodies.size(); ++a)
    for (std::size_t b = a + 1; b < bodies.size(); ++b)
      if (find(int(a)) == find(int(b))) pairs.push_back({int(a), int(b)});
  return pairs;
}

}  // namespace

RigidFamily::RigidFamily(const SceneDef& scene, std::span<const std::shared_ptr<const MeshSdf>> mesh_fields)
    : body_mesh_fields_(scene.rigid_bodies),
      gravity_(to_d(scene.solver.gravity)),
      lowest_corner_(to_d(scene.domain.min)),
      h_(scene.solver.frame_dt / scene.solver.substeps) {
  std::vector<double> extent;
  bodies_ = make_bodies(scene, extent);
  joints_ = rigid::JointSolver(make_joints(scene, bodies_, extent), bodies_, scene.solver.joint_trees, gravity_);
  contacts_ = rigid::WorldContacts(scene, h_, mesh_fields);
  body_contacts_ = rigid::BodyContacts(scene, contactless_pairs(joints_.joints(), bodies_), h_, body_mesh_fields_);
  start_energy_ = energy();
}

void RigidFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"body predict", Stage::Predict, pass_order::kBodyPredict, true, [this](const StepContext&) {
                      predict();
                    }});
  passes.push_back({"body update", Stage::Update, pass_order::kBodyUpdate, true, [this](const StepContext&) {
                      update();
                    }});
  // With the world, then between bodies (which reads which bodies the world holds).
  passes.push_back({"body contacts", Stage::Iterate, pass_order::kBodyContacts, true, [this](const StepContext&) {
                      contacts_.solve_positions(bodies_);
                      if (!body_contacts_.empty()) body_contacts_.solve_positions(bodies_, contacts_);
                    }});
  passes.push_back({"body contact velocities", Stage::Update, pass_order::kBodyContactVelocities, true,
                    [this](const StepContext&) {
                      contacts_.solve_velocities(bodies_);
                      if (!body_contacts_.empty()) body_contacts_.solve_velocities(bodies_);
                    }});
  if (joints_.empty()) return;
  passes.push_back({"joints reset", Stage::BeginSubstep, pass_order::kJointReset, false,
                    [this](const StepContext&) { joints_.reset_multipliers(); }});
  passes.push_back({"joints", Stage::Iterate, pass_order::kJoints, true,
                    [this](const StepContext&) { joints_.solve(bodies_, h_); }});
}

void RigidFamily::predict() {
  joints_.begin_substep(bodies_);
  contacts_.begin_substep(bodies_);
  if (!body_contacts_.empty()) body_contacts_.begin_substep(bodies_);
  for (RigidBody& b : bodies_) rigid::predict_body(b, gravity_, h_);
}

void RigidFamily::update() {
  for (RigidBody& b : bodies_) rigid::update_body_velocity(b, h_);
}

double RigidFamily::energy() const {
  double e = 0.0;
  for (const RigidBody& b : bodies_)
    if (!b.fixed()) e += rigid::kinetic_energy(b) - dot(gravity_, b.x - lowest_corner_) / b.inverse_mass;
  return e;
}

std::vector<BodyPose> RigidFamily::poses() const {
  std::vector<BodyPose> poses;
  for (const RigidBody& b : bodies_)
    poses.push_back({{b.x.x, b.x.y, b.x.z}, {b.q.w, b.q.x, b.q.y, b.q.z}, {b.v.x, b.v.y, b.v.z},
                     {b.omega.x, b.omega.y, b.omega.z}});
  return poses;
}

void RigidFamily::measure(FrameMetrics& m) {
  for (const RigidBody& b : bodies_)
    for (double value : {b.x.x, b.x.y, b.x.z, b.q.w, b.q.x, b.q.y, b.q.z, b.v.x, b.v.y, b.v.z, b.omega.x, b.omega.y,
                         b.omega.z})
      if (!std::isfinite(value)) ++m.non_finite;
  if (!joints_.empty()) {
    double drift_sum = 0.0, drift_max = 0.0, angle_sum = 0.0, angle_max = 0.0;
    std::size_t angular = 0;
    for (const Joint& j : joints_.joints()) {
      const rigid::JointSolver::Error e = joints_.error(j, bodies_);
      const double drift = e.distance / j.length;
      drift_sum += drift, drift_max = std::max(drift_max, drift);
      if (j.type == JointType::Ball || j.type == JointType::Distance) continue;
      ++angular;
      angle_sum += e.angle, angle_max = std::max(angle_max, e.angle);
    }
    const double count = double(joints_.joints().size());
    m.errors.push_back({"joint_drift", "joint drift", ErrorUnit::Ratio, drift_sum / count, drift_max});
    if (angular > 0)
      m.errors.push_back({"joint_angle_error", "joint angle", ErrorUnit::Radians, angle_sum / double(angular),
                          angle_max});
  }
  // Relative to E_0; to 1 J when E_0 is 0 (every body fixed, or at rest with its centre on the
  // domain's lowest corner).
  const double change = std::fabs(energy() - start_energy_) / (start_energy_ != 0.0 ? std::fabs(start_energy_) : 1.0);
  m.errors.push_back({"body_energy", "body energy change", ErrorUnit::Ratio, change, change});
}

void RigidFamily::save_state(CheckpointChunks& chunks) const {
  std::vector<SavedBody> saved;
  for (const RigidBody& b : bodies_) saved.push_back({b.x, b.q, b.v, b.omega});
  chunks.put_values(kBodiesChunk, std::span<const SavedBody>(saved));
  const std::vector<Vec3d> lambdas = joints_.tree_multipliers();
  if (!lambdas.empty()) chunks.put_values(kTreesChunk, std::span<const Vec3d>(lambdas));
}

void RigidFamily::restore_state(const CheckpointChunks& chunks) {
  std::vector<SavedBody> saved(bodies_.size());
  chunks.get_values(kBodiesChunk, std::span<SavedBody>(saved));
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    RigidBody& b = bodies_[k];
    b.x = b.x_prev = saved[k].x;
    b.q = b.q_prev = saved[k].q;
    b.v = saved[k].v;
    b.omega = saved[k].omega;
  }
  std::vector<Vec3d> lambdas = joints_.tree_multipliers();
  if (lambdas.empty()) return;
  chunks.get_values(kTreesChunk, std::span<Vec3d>(lambdas));
  joints_.restore_tree_multipliers(lambdas);
}

}  // namespace seiche
