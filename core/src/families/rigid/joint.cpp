// The joints' XPBD solve (the constraints are in joint.hpp, the corrections in
// body_correction.hpp).
#include "joint.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "body_correction.hpp"
#include "hinge_limit.hpp"

namespace seiche::rigid {

namespace {

double hinge_angle_of(const Joint& j, const RigidBody& a, const RigidBody& b) {
  const Vec3d axis = rotate(a.q, j.axis_a);
  const Vec3d from = rotate(a.q, j.normal_a), to = rotate(b.q, j.normal_b);
  return portable_atan2(dot(cross(from, to), axis), dot(from, to));
}

// The universal joint's angular error: the rotation vector that turns unit v (body b's axis) from
// perpendicular to unit u (body a's), -atan2(u . v, |u x v|) (u x v) / |u x v| (zero when they are
// parallel, where no direction is preferred).
Vec3d off_perpendicular(Vec3d u, Vec3d v) {
  const Vec3d c = cross(u, v);
  const double s = length(c);
  if (!(s > 0.0)) return {};
  return (-portable_atan2(dot(u, v), s) / s) * c;
}

double slider_position_of(const Joint& j, const RigidBody& a, const RigidBody& b) {
  const Vec3d d = (b.x + rotate(b.q, j.anchor_b)) - (a.x + rotate(a.q, j.anchor_a));
  return dot(d, rotate(a.q, j.axis_a));
}

// The positional error the joint corrects: P_b - P_a, less what its type allows.
[[gnu::always_inline]] inline Vec3d positional_error(const Joint& j, const RigidBody& a, const RigidBody& b, Vec3d r_a, Vec3d r_b) {
  const Vec3d d = (b.x + r_b) - (a.x + r_a);
  if (j.type == JointType::Distance) {
    const double l = length(d);
    return (l - std::clamp(l, j.min_distance, j.max_distance)) * normalized_or_zero(d);
  }
  if (j.type == JointType::Slider) {
    const Vec3d axis = rotate(a.q, j.axis_a);
    const double along = dot(d, axis);
    return d - (j.limited ? std::clamp(along, j.lower, j.upper) : along) * axis;
  }
  return d;
}

// The fixed joint's (and slider's) angular error: the rotation vector of q_b (q_a q_rest)^-1.
Vec3d fixed_rotation_error(const Joint& j, const RigidBody& a, const RigidBody& b) {
  return rotation_vector(b.q * conjugate(a.q * j.rest_rotation));
}

// The universal joint's alignment: a_a and a_b perpendicular. Out of the joint loop (noinline),
// like the motor below, so that the loop's code for the other types stays as compact as it was.
[[gnu::noinline]] void correct_universal(Joint& j, RigidBody& a, RigidBody& b, double alpha) {
  correct_rotation(a, b, off_perpendicular(rotate(a.q, j.axis_a), rotate(b.q, j.axis_b)), alpha, j.lambda_align);
}

// A motor's drive: a hinge's angle or a slider's position to its target (a velocity motor's
// target: where it started the substep plus its rate times h).
[[gnu::noinline]] void drive_motor(Joint& j, RigidBody& a, RigidBody& b, double h, double inverse_h2) {
  const double target = j.motor == MotorMode::Position ? j.target : j.motor_start + j.target * h;
  const double motor_alpha = j.motor_compliance * inverse_h2;
  if (j.type == JointType::Slider) {
    const double off = slider_position_of(j, a, b) - target;
    correct_position(a, b, rotate(a.q, j.anchor_a), rotate(b.q, j.anchor_b), off * rotate(a.q, j.axis_a), motor_alpha,
                     j.lambda_motor);
  } else {
    const double off = wrap_angle(hinge_angle_of(j, a, b) - target);
    correct_rotation(a, b, off * rotate(a.q, j.axis_a), motor_alpha, j.lambda_motor);
  }
}

// What the tree solve leaves of a hinge or slider in it (joint_tree.hpp): its limit (an
// inequality) and its motor (its own compliance), by Gauss-Seidel after the tree.
[[gnu::noinline]] void correct_limit_and_motor(Joint& j, RigidBody& a, RigidBody& b, double h, double inverse_h2) {
  if (j.limited) {
    const double alpha = j.compliance * inverse_h2;
    const Vec3d axis = rotate(a.q, j.axis_a);
    if (j.type == JointType::Hinge) {
      const double phi = hinge_angle_of(j, a, b);
      const double over = phi - std::clamp(phi, j.lower, j.upper);
      if (over != 0.0)
        correct_limit_at_anchor(a, b, rotate(a.q, j.anchor_a), rotate(b.q, j.anchor_b), axis, over, alpha, j.lambda_limit);
    } else {
      const double s = slider_position_of(j, a, b);
      const double over = s - std::clamp(s, j.lower, j.upper);
      if (over != 0.0)
        correct_position(a, b, rotate(a.q, j.anchor_a), rotate(b.q, j.anchor_b), over * axis, alpha, j.lambda_limit);
    }
  }
  if (j.motor != MotorMode::None) drive_motor(j, a, b, h, inverse_h2);
}

// Whether joint j has a part that is not an equality row: a limit or a motor.
bool has_limit_or_motor(const Joint& j) {
  return (j.type == JointType::Hinge || j.type == JointType::Slider) && (j.limited || j.motor != MotorMode::None);
}

}  // namespace

double wrap_angle(double angle) {
  constexpr double pi = std::numbers::pi;
  return angle - 2.0 * pi * std::floor((angle + pi) / (2.0 * pi));
}

double JointSolver::hinge_angle(const Joint& j, std::span<const RigidBody> bodies) const {
  if (j.type != JointType::Hinge) return 0.0;
  const RigidBody& a = j.body_a < 0 ? world_ : bodies[std::size_t(j.body_a)];
  const RigidBody& b = j.body_b < 0 ? world_ : bodies[std::size_t(j.body_b)];
  return hinge_angle_of(j, a, b);
}

double JointSolver::slider_position(const Joint& j, std::span<const RigidBody> bodies) const {
  if (j.type != JointType::Slider) return 0.0;
  const RigidBody& a = j.body_a < 0 ? world_ : bodies[std::size_t(j.body_a)];
  const RigidBody& b = j.body_b < 0 ? world_ : bodies[std::size_t(j.body_b)];
  return slider_position_of(j, a, b);
}

JointSolver::JointSolver(std::vector<Joint> joints, std::span<const RigidBody> bodies, bool trees, Vec3d gravity)
    : joints_(std::move(joints)), in_tree_(joints_.size(), 0) {
  if (trees) take_trees(bodies, gravity);
  std::vector<JointEnds> ends;
  const auto movable = [&](int body) { return body >= 0 && !bodies[std::size_t(body)].fixed() ? body : -1; };
  for (std::size_t k = 0; k < joints_.size(); ++k)
    if (!in_tree_[k] || has_limit_or_motor(joints_[k])) ends.push_back({k, movable(joints_[k].body_a), movable(joints_[k].body_b)});
  colours_ = JointColours(ends, bodies.size());
}

void JointSolver::take_trees(std::span<const RigidBody> bodies, Vec3d gravity) {
  std::vector<TreeLink> links;
  std::vector<std::size_t> joint_of;
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    if (j.type == JointType::Distance) continue;  // an inequality: Gauss-Seidel
    const TreeJointType type = j.type == JointType::Ball        ? TreeJointType::Ball
                               : j.type == JointType::Hinge     ? TreeJointType::Hinge
                               : j.type == JointType::Fixed     ? TreeJointType::Fixed
                               : j.type == JointType::Slider    ? TreeJointType::Slider
                                                                : TreeJointType::Universal;
    links.push_back({type, j.body_a, j.body_b, j.anchor_a, j.anchor_b, j.axis_a, j.axis_b, j.normal_a, j.rest_rotation,
                     j.compliance});
    joint_of.push_back(k);
  }
  trees_ = JointTreeSolver(links, bodies, gravity);
  for (std::size_t l = 0; l < links.size(); ++l) in_tree_[joint_of[l]] = trees_.in_forest(l) ? 1 : 0;
  // The start directions only where no Gauss-Seidel correction acts on a tree's bodies (a joint
  // left out, a limit, a motor) and only over the joint types they were measured with (ball,
  // hinge, fixed; joint_tree.hpp).
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    const bool measured_type = j.type == JointType::Ball || j.type == JointType::Hinge || j.type == JointType::Fixed;
    if (!in_tree_[k] || has_limit_or_motor(j) || !measured_type)
      trees_.keep_end_directions_at(j.body_a), trees_.keep_end_directions_at(j.body_b);
  }
}

std::size_t JointSolver::tree_joints() const { return std::size_t(std::count(in_tree_.begin(), in_tree_.end(), 1)); }

void JointSolver::begin_substep(std::span<const RigidBody> bodies) {
  for (Joint& j : joints_)
    if (j.motor == MotorMode::Velocity)
      j.motor_start = j.type == JointType::Slider ? slider_position(j, bodies) : hinge_angle(j, bodies);
}

void JointSolver::reset_multipliers() {
  for (Joint& j : joints_) j.lambda_position = j.lambda_align = j.lambda_limit = j.lambda_motor = 0.0;
  trees_.reset_multipliers();
}

void JointSolver::solve(std::span<RigidBody> bodies, double h) {
  trees_.solve(bodies, h);
  const double inverse_h2 = 1.0 / (h * h);
  for (std::size_t c = 0; c < colours_.colour_count(); ++c) {
    const std::span<const std::size_t> members = colours_.colour(c);
    if (members.size() < kParallelColour) {
      for (std::size_t k : members) solve_joint(k, bodies, h, inverse_h2);
      continue;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, members.size(), kParallelGrain), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) solve_joint(members[i], bodies, h, inverse_h2);
    });
  }
}

// Inlined into both loops of solve (with positional_error), the rarer parts out of line: the
// joint loop as fast as the single serial loop it replaced (measured, 1000 hinges).
[[gnu::always_inline]] inline void JointSolver::solve_joint(std::size_t k, std::span<RigidBody> bodies, double h, double inverse_h2) {
  Joint& j = joints_[k];
  RigidBody& a = j.body_a < 0 ? world_ : bodies[std::size_t(j.body_a)];
  RigidBody& b = j.body_b < 0 ? world_ : bodies[std::size_t(j.body_b)];
  if (in_tree_[k]) return correct_limit_and_motor(j, a, b, h, inverse_h2);
  const double alpha = j.compliance * inverse_h2;
  if (j.type == JointType::Hinge) {
    correct_rotation(a, b, rotation_between(rotate(a.q, j.axis_a), rotate(b.q, j.axis_b)), alpha, j.lambda_align);
    const Vec3d axis = rotate(a.q, j.axis_a);
    if (j.limited) {
      const double phi = hinge_angle_of(j, a, b);
      const double over = phi - std::clamp(phi, j.lower, j.upper);
      if (over != 0.0) correct_rotation(a, b, over * axis, alpha, j.lambda_limit);
    }
  } else if (j.type == JointType::Fixed || j.type == JointType::Slider) {
    correct_rotation(a, b, fixed_rotation_error(j, a, b), alpha, j.lambda_align);
  } else if (j.type == JointType::Universal) {
    correct_universal(j, a, b, alpha);
  }
  const Vec3d r_a = rotate(a.q, j.anchor_a), r_b = rotate(b.q, j.anchor_b);
  correct_position(a, b, r_a, r_b, positional_error(j, a, b, r_a, r_b), alpha, j.lambda_position);
  if (j.motor != MotorMode::None) drive_motor(j, a, b, h, inverse_h2);  // last: what the iteration ends on
}

JointSolver::Error JointSolver::error(const Joint& j, std::span<const RigidBody> bodies) const {
  const RigidBody& a = j.body_a < 0 ? world_ : bodies[std::size_t(j.body_a)];
  const RigidBody& b = j.body_b < 0 ? world_ : bodies[std::size_t(j.body_b)];
  Error e;
  e.distance = length(positional_error(j, a, b, rotate(a.q, j.anchor_a), rotate(b.q, j.anchor_b)));
  if (j.type == JointType::Hinge) {
    e.angle = length(rotation_between(rotate(a.q, j.axis_a), rotate(b.q, j.axis_b)));
    if (j.limited) {
      const double phi = hinge_angle_of(j, a, b);
      e.angle += std::fabs(phi - std::clamp(phi, j.lower, j.upper));
    }
  } else if (j.type == JointType::Fixed || j.type == JointType::Slider) {
    e.angle = length(fixed_rotation_error(j, a, b));
  } else if (j.type == JointType::Universal) {
    e.angle = length(off_perpendicular(rotate(a.q, j.axis_a), rotate(b.q, j.axis_b)));
  }
  return e;
}

}  // namespace seiche::rigid
