// Contacts between rigid bodies, friction and restitution (the math is in body_contacts.hpp).
#include "body_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "body_correction.hpp"
#include "body_shape.hpp"
#include "body_solid.hpp"
#include "body_surface.hpp"
#include "box_box.hpp"
#include "capsule_sides.hpp"

namespace seiche::rigid {

namespace {

// As for the world contacts (world_contacts.cpp): the normals' Jacobi passes stop where no point
// is deeper than kResolved (m), or after kNormalPasses.
constexpr double kResolved = 1e-12;
constexpr int kNormalPasses = 32;
// Shock propagation: a normal within 45 degrees of the vertical.
const double kSupportCosine = std::sqrt(0.5);

enum FixedSide : int { kNeither = 0, kFixedA = 1, kFixedB = 2 };

double mixed(double a, double b) { return std::sqrt(a * b); }

// The generalized inverse mass of the pair at levers r_a, r_b along unit n, a side treated as
// fixed counting 0.
double pair_inverse_mass(const RigidBody& a, const RigidBody& b, Vec3d r_a, Vec3d r_b, Vec3d n, int fixed) {
  return (fixed == kFixedA ? 0.0 : positional_inverse_mass(a, r_a, n)) +
         (fixed == kFixedB ? 0.0 : positional_inverse_mass(b, r_b, n));
}

// The relative velocity of a's point r_a and b's point r_b.
Vec3d relative_velocity(Vec3d v_a, Vec3d omega_a, Vec3d v_b, Vec3d omega_b, Vec3d r_a, Vec3d r_b) {
  return (v_a + cross(omega_a, r_a)) - (v_b + cross(omega_b, r_b));
}

// A mesh body's large triangles (area above (extent / 8)^2): each corner moved a third of the way
// to the triangle's centroid, as a point of radius 0 (body_contacts.hpp).
void append_face_points(const BodySurface& surface, double extent, std::vector<ContactPoint>& out) {
  const double large = (extent / 8.0) * (extent / 8.0);
  for (const auto& t : surface.triangles) {
    const Vec3d p[3] = {surface.vertices[t[0]], surface.vertices[t[1]], surface.vertices[t[2]]};
    if (!(0.5 * length(cross(p[1] - p[0], p[2] - p[0])) > large)) continue;
    const Vec3d centroid = (1.0 / 3.0) * (p[0] + p[1] + p[2]);
    for (const Vec3d& corner : p) out.push_back({corner + (1.0 / 3.0) * (centroid - corner), 0.0});
  }
}

}  // namespace

BodyContacts::BodyContacts(const SceneDef& scene, const std::vector<std::pair<int, int>>& jointed, double substep,
                           BodyMeshFields& mesh_fields)
    : h_(substep) {
  const Vec3 g = scene.solver.gravity;
  const Vec3d gravity{double(g[0]), double(g[1]), double(g[2])};
  up_ = -normalized_or_zero(gravity);
  rest_speed_ = 2.0 * length(gravity) * h_;
  const std::size_t count = scene.rigid_bodies.size();
  std::vector<std::pair<int, int>> apart;  // the pairs without contact, (lower, higher), sorted
  for (const auto& [a, b] : jointed) apart.push_back({std::min(a, b), std::max(a, b)});
  std::sort(apart.begin(), apart.end());
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t j = i + 1; j < count; ++j) {
      if (scene.rigid_bodies[i].fixed && scene.rigid_bodies[j].fixed) continue;
      if (!std::binary_search(apart.begin(), apart.end(), std::pair{int(i), int(j)})) candidates_.push_back({int(i), int(j)});
    }
  if (candidates_.empty()) return;
  for (std::size_t k = 0; k < count; ++k) {
    const RigidBodyDef& def = scene.rigid_bodies[k];
    Body b;
    b.first_point = int(points_.size());
    for (const ContactPoint& p : contact_points(def)) points_.push_back(p);
    const ShapeDims dims = body_shape_def(def);
    if (dims.shape == BodyShape::Mesh) append_face_points(body_surface(def), mass_properties(dims).extent, points_);
    b.first_axis_point = int(points_.size());
    for (const ContactPoint& p : capsule_axis_points(def)) points_.push_back(p);
    b.end_point = int(points_.size());
    if (dims.shape == BodyShape::Mesh) mesh_sdfs_.push_back(mesh_fields.get(k));
    b.solid = body_solid(dims, dims.shape == BodyShape::Mesh ? mesh_sdfs_.back().get() : nullptr);
    b.extent = mass_properties(dims).extent;
    b.static_friction = def.friction, b.dynamic_friction = def.dynamic_friction, b.restitution = def.restitution;
    bodies_.push_back(b);
  }
  resting_.resize(count);
  reach_.resize(count);
  v_before_.resize(count);
  omega_before_.resize(count);
}

void BodyContacts::begin_substep(const std::vector<RigidBody>& bodies) {
  for (std::size_t k = 0; k < bodies.size(); ++k) v_before_[k] = bodies[k].v, omega_before_[k] = bodies[k].omega;
  pairs_found_ = false;
}

void BodyContacts::find_pairs(const std::vector<RigidBody>& bodies) {
  active_.clear();
  slots_.clear();
  // Each body's bounding ball grown by what it moves in a substep (the corrections within it are
  // small: a contact they would cause is found in the next substep).
  for (std::size_t k = 0; k < bodies.size(); ++k) reach_[k] = bodies_[k].extent + length(bodies[k].v) * h_;
  for (std::size_t candidate = 0; candidate < candidates_.size(); ++candidate) {
    const auto [i, j] = candidates_[candidate];
    const RigidBody &a = bodies[std::size_t(i)], &b = bodies[std::size_t(j)];
    const double reach = reach_[std::size_t(i)] + reach_[std::size_t(j)];
    const Vec3d d = a.x - b.x;
    if (!(dot(d, d) < reach * reach)) continue;
    Active pair;
    pair.a = i, pair.b = j, pair.candidate = int(candidate);
    pair.height = std::min(dot(a.x, up_), dot(b.x, up_));
    active_.push_back(pair);
  }
  // From the lowest pair up; ties (and every pair without gravity) in the candidates' order.
  std::sort(active_.begin(), active_.end(), [](const Active& p, const Active& q) {
    return p.height != q.height ? p.height < q.height : p.candidate < q.candidate;
  });
  for (Active& pair : active_) {
    pair.first_slot = int(slots_.size());
    for (const auto& [body, of_a] : {std::pair{pair.a, true}, std::pair{pair.b, false}}) {
      const Body& own = bodies_[std::size_t(body)];
      // A capsule's axis balls against a mesh body only (world_contacts.hpp).
      const bool other_is_mesh = bodies_[std::size_t(of_a ? pair.b : pair.a)].solid.shape == ColliderDef::Shape::Mesh;
      const int end = other_is_mesh ? own.end_point : own.first_axis_point;
      for (int point = own.first_point; point < end; ++point) {
        Slot s;
        s.point = point, s.of_a = of_a;
        slots_.push_back(s);
      }
    }
    // A capsule's side against a capsule or a box: one slot per role (capsule_sides.hpp).
    pair.first_side_slot = int(slots_.size());
    if (has_capsule_sides(bodies_[std::size_t(pair.a)].solid, bodies_[std::size_t(pair.b)].solid))
      for (int role = 0; role < kCapsuleSideRoles; ++role) {
        Slot side;
        side.point = -1;  // no ball: the segment's point of that role
        slots_.push_back(side);
      }
    pair.end_slot = int(slots_.size());
  }
  pairs_found_ = true;
}

void BodyContacts::solve_positions(std::vector<RigidBody>& bodies, const WorldContacts& world) {
  if (!pairs_found_) find_pairs(bodies);
  if (active_.empty()) return;
  world.held_up(resting_, up_, kSupportCosine);
  for (std::size_t k = 0; k < bodies.size(); ++k) resting_[k] = resting_[k] || bodies[k].fixed();
  for (Active& pair : active_) solve_pair(pair, bodies[std::size_t(pair.a)], bodies[std::size_t(pair.b)]);
}

void BodyContacts::solve_pair(Active& pair, RigidBody& a, RigidBody& b) {
  const Body &body_a = bodies_[std::size_t(pair.a)], &body_b = bodies_[std::size_t(pair.b)];
  const bool a_resting = resting_[std::size_t(pair.a)], b_resting = resting_[std::size_t(pair.b)];
  for (int s = pair.first_slot; s < pair.end_slot; ++s) slots_[std::size_t(s)].touching = false;
  const bool boxes = body_a.solid.shape == ColliderDef::Shape::Box && body_b.solid.shape == ColliderDef::Shape::Box;
  // The normals: every point from the same poses (Jacobi), applied together (with the step that
  // fits them best, below), until resolved.
  bool touched = false, supports = false;
  for (int pass = 0; pass < kNormalPasses; ++pass) {
    const RigidBody a0 = a, b0 = b;
    touches_.clear();
    Vec3d pushed{};  // the normals weighted by their depths: the way the pair is pushed apart
    if (boxes) {  // by separating axes and clipping (box_box.hpp); a slot per touching feature
      BoxBoxContact found[kMaxBoxBoxContacts];
      const int count = box_box_contacts(a0, body_a.solid.b, b0, body_b.solid.b, found);
      ++pass_stamp_;
      for (int k = 0; k < count; ++k) {
        const BoxBoxContact& f = found[k];
        const int slot = feature_slot(pair, f.feature);
        if (slot < 0) continue;  // every slot taken in this iteration: found again in the next pass
        touches_.push_back({slot, f.point_a - a0.x, f.point_b - b0.x, f.normal, f.depth, 0.0});
        pushed += f.depth * f.normal;
      }
    }
    for (int s = pair.first_slot; s < pair.first_side_slot && !boxes; ++s) {
      const Slot& slot = slots_[std::size_t(s)];
      const ContactPoint& c = points_[std::size_t(slot.point)];
      // The ball in the other body's frame, against its solid.
      const RigidBody& own = slot.of_a ? a0 : b0;
      const RigidBody& other = slot.of_a ? b0 : a0;
      const Vec3d centre = own.world_point(c.centre);
      const Vec3d in_other = rotate_back(other.q, centre - other.x);
      const SolidSurface& other_solid = (slot.of_a ? body_b : body_a).solid;
      SurfacePenetration pen;
      if (!penetration(other_solid, in_other, c.radius, pen)) continue;
      const Vec3d m = rotate(other.q, pen.normal);  // out of the other body, world frame
      if (!(dot(m, m) > 0.5)) continue;  // no direction (a mesh field's flat spot): no contact
      const Vec3d own_point = centre - c.radius * m, other_point = own_point + pen.depth * m;
      const Vec3d p_a = slot.of_a ? own_point : other_point, p_b = slot.of_a ? other_point : own_point;
      const Vec3d n = slot.of_a ? m : -m;
      touches_.push_back({s, p_a - a0.x, p_b - b0.x, n, pen.depth, 0.0});
      pushed += pen.depth * n;
    }
    if (pair.first_side_slot < pair.end_slot) {  // a capsule's side (capsule_sides.hpp)
      BoxBoxContact found[kCapsuleSideRoles];
      capsule_side_contacts(a0, body_a.solid, b0, body_b.solid, found);
      for (int role = 0; role < kCapsuleSideRoles; ++role) {
        const BoxBoxContact& f = found[role];
        if (!(f.depth > 0.0)) continue;
        touches_.push_back({pair.first_side_slot + role, f.point_a - a0.x, f.point_b - b0.x, f.normal, f.depth, 0.0});
        pushed += f.depth * f.normal;
      }
    }
    if (touches_.empty()) break;
    // Shock propagation: the lower body of a vertical contact, resting, carries the upper, unless
    // the upper is fixed (a slab pressing down on it): then the lower is the one to move.
    const double vertical = dot(normalized_or_zero(pushed), up_);
    const int fixed = vertical > kSupportCosine && b_resting && !a.fixed()    ? kFixedB
                      : vertical < -kSupportCosine && a_resting && !b.fixed() ? kFixedA
                                                                              : kNeither;
    double deepest = 0.0;
    for (Touch& t : touches_) {
      const double w = pair_inverse_mass(a0, b0, t.r_a, t.r_b, t.normal, fixed);
      t.dlambda = w > 0.0 ? t.depth / w : 0.0;
      deepest = std::max(deepest, t.depth);
    }
    pair.fixed = fixed;
    const double step = best_step(a0, b0, fixed);
    for (const Touch& t : touches_) {
      if (!(t.dlambda > 0.0)) continue;
      Slot& slot = slots_[std::size_t(t.slot)];
      const double dlambda_n = step * t.dlambda;
      slot.normal = t.normal;
      slot.local_a = rotate_back(a0.q, t.r_a), slot.local_b = rotate_back(b0.q, t.r_b);
      slot.lambda_n += dlambda_n;
      slot.touching = true;
      pair.lambda_n += dlambda_n;
      touched = true;
      supports = supports || fixed != kNeither;
    }
    apply_positions(a, b, step, fixed);
    if (!(deepest > kResolved)) break;
  }
  if (!touched) return;
  // What rests on a resting body rests too (for the pairs above it, later in the order).
  if (supports) resting_[std::size_t(pair.a)] = resting_[std::size_t(pair.b)] = 1;
  // Static friction, within the cone of the pair: a face as one patch (face_friction), else every
  // touching point's impulse from the same poses, applied together with the best step.
  const double mu_s = mixed(body_a.static_friction, body_b.static_friction);
  if (!(mu_s > 0.0) || !(pair.lambda_n > 0.0)) return;
  if (face_friction(pair, a, b, mu_s)) return;
  const RigidBody a0 = a, b0 = b;
  touches_.clear();
  for (int s = pair.first_slot; s < pair.end_slot; ++s) {
    const Slot& slot = slots_[std::size_t(s)];
    if (!slot.touching) continue;
    const Vec3d moved_a = a0.world_point(slot.local_a) - (a0.x_prev + rotate(a0.q_prev, slot.local_a));
    const Vec3d moved_b = b0.world_point(slot.local_b) - (b0.x_prev + rotate(b0.q_prev, slot.local_b));
    const Vec3d slip_vector = moved_a - moved_b;
    const Vec3d tangential = slip_vector - dot(slip_vector, slot.normal) * slot.normal;
    const double slip = length(tangential);
    if (!(slip > 0.0)) continue;
    const Vec3d back = -(1.0 / slip) * tangential;  // the way a's point is to move
    const Vec3d r_a = rotate(a0.q, slot.local_a), r_b = rotate(b0.q, slot.local_b);
    const double w_t = pair_inverse_mass(a0, b0, r_a, r_b, back, pair.fixed);
    if (!(w_t > 0.0)) continue;
    touches_.push_back({s, r_a, r_b, back, slip, slip / w_t});
  }
  if (touches_.empty()) return;
  const double step = best_step(a0, b0, pair.fixed);
  Vec3d sum{};
  for (const Touch& t : touches_) sum += (step * t.dlambda) * t.normal;
  if (!(length(pair.lambda_t + sum) < mu_s * pair.lambda_n)) return;  // slides
  pair.lambda_t += sum;
  apply_positions(a, b, step, pair.fixed);
}

int BodyContacts::feature_slot(const Active& pair, int feature) {
  int free = -1, stale = -1;
  for (int s = pair.first_slot; s < pair.end_slot; ++s) {
    Slot& slot = slots_[std::size_t(s)];
    if (slot.feature == feature) {
      slot.stamp = pass_stamp_;
      return s;
    }
    if (slot.feature < 0) {
      if (free < 0) free = s;
    } else if (stale < 0 && !slot.touching && slot.stamp != pass_stamp_) {
      stale = s;
    }
  }
  const int s = free >= 0 ? free : stale;
  if (s < 0) return -1;
  Slot& slot = slots_[std::size_t(s)];
  slot = Slot{};
  slot.feature = feature, slot.stamp = pass_stamp_;
  return s;
}

bool BodyContacts::face_friction(Active& pair, RigidBody& a, RigidBody& b, double mu_s) {
  // The face: 3 touching points or more, their centre weighted by their normal multipliers.
  Vec3d centre{}, normal{};
  double weight = 0.0;
  int count = 0;
  for (int s = pair.first_slot; s < pair.end_slot; ++s) {
    const Slot& slot = slots_[std::size_t(s)];
    if (!slot.touching) continue;
    ++count;
    centre += slot.lambda_n * a.world_point(slot.local_a);
    normal += slot.lambda_n * slot.normal;
    weight += slot.lambda_n;
  }
  if (count < 3 || !(weight > 0.0)) return false;
  centre = (1.0 / weight) * centre;
  const Vec3d n = normalized_or_zero(normal);
  double spread = 0.0;  // rho: the points' weighted mean distance from the centre
  for (int s = pair.first_slot; s < pair.end_slot; ++s) {
    const Slot& slot = slots_[std::size_t(s)];
    if (slot.touching) spread += slot.lambda_n * length(a.world_point(slot.local_a) - centre);
  }
  spread /= weight;
  const bool moves_a = pair.fixed != kFixedA && !a.fixed(), moves_b = pair.fixed != kFixedB && !b.fixed();
  // Along the surface: one constraint at the centre, moving the bodies along it and turning them
  // about n only (the normals hold the tipping).
  const RigidBody a0 = a, b0 = b;
  const Vec3d r_a = centre - a0.x, r_b = centre - b0.x;
  const Vec3d local_a = rotate_back(a0.q, r_a), local_b = rotate_back(b0.q, r_b);
  const Vec3d moved = (centre - (a0.x_prev + rotate(a0.q_prev, local_a))) - (centre - (b0.x_prev + rotate(b0.q_prev, local_b)));
  const Vec3d tangential = moved - dot(moved, n) * n;
  const double slip = length(tangential);
  if (slip > 0.0) {
    const Vec3d t = (1.0 / slip) * tangential;
    const double w_t = (moves_a ? patch_inverse_mass(a0, r_a, t, n) : 0.0) + (moves_b ? patch_inverse_mass(b0, r_b, t, n) : 0.0);
    const Vec3d impulse = w_t > 0.0 ? -(slip / w_t) * t : Vec3d{};
    if (w_t > 0.0 && length(pair.lambda_t + impulse) < mu_s * pair.lambda_n) {
      pair.lambda_t += impulse;
      if (moves_a) a.x += a.inverse_mass * impulse, a.q = rotate_by_small(a.q, (dot(cross(r_a, impulse), n) * angular_inverse_mass(a0, n)) * n);
      if (moves_b) b.x -= b.inverse_mass * impulse, b.q = rotate_by_small(b.q, -(dot(cross(r_b, impulse), n) * angular_inverse_mass(b0, n)) * n);
    }
  }
  // The relative turn about n since the substep began, undone where the torque stays within what
  // the points' friction holds at their distance from the centre: mu_s lambda_n rho.
  const double turn = dot(rotation_vector(a.q * conjugate(a.q_prev)) - rotation_vector(b.q * conjugate(b.q_prev)), n);
  const double w_n = (moves_a ? angular_inverse_mass(a, n) : 0.0) + (moves_b ? angular_inverse_mass(b, n) : 0.0);
  if (!(w_n > 0.0)) return true;
  const double twist = -turn / w_n;
  if (std::fabs(pair.twist + twist) < mu_s * pair.lambda_n * spread) {
    pair.twist += twist;
    if (moves_a) apply_angular_impulse(a, twist * n);
    if (moves_b) apply_angular_impulse(b, -twist * n);
  }
  return true;
}

BodyContacts::Sums BodyContacts::sums(double step) const {
  Sums total;
  for (const Touch& t : touches_) {
    const Vec3d p = (step * t.dlambda) * t.normal;
    total.impulse += p, total.moment_a += cross(t.r_a, p), total.moment_b += cross(t.r_b, p);
  }
  return total;
}

double BodyContacts::best_step(const RigidBody& a, const RigidBody& b, int fixed) const {
  // The bodies' moves under all the impulses together: dx = sum p / m, dtheta = I^-1 sum r x p.
  const Sums total = sums(1.0);
  const bool moves_a = fixed != kFixedA, moves_b = fixed != kFixedB;
  const Vec3d dx_a = moves_a ? a.inverse_mass * total.impulse : Vec3d{};
  const Vec3d dtheta_a = moves_a ? a.world_inverse_inertia(total.moment_a) : Vec3d{};
  const Vec3d dx_b = moves_b ? -(b.inverse_mass * total.impulse) : Vec3d{};
  const Vec3d dtheta_b = moves_b ? -b.world_inverse_inertia(total.moment_b) : Vec3d{};
  // Each point's depth change dd_j = n_j.((dx_a + dtheta_a x r_a) - (dx_b + dtheta_b x r_b)).
  double fit = 0.0, size = 0.0;
  for (const Touch& t : touches_) {
    const double change = dot(t.normal, (dx_a + cross(dtheta_a, t.r_a)) - (dx_b + cross(dtheta_b, t.r_b)));
    fit += t.depth * change, size += change * change;
  }
  return size > 0.0 ? std::clamp(fit / size, 0.0, 1.0) : 1.0;
}

void BodyContacts::apply_positions(RigidBody& a, RigidBody& b, double step, int fixed) const {
  const Sums total = sums(step);
  if (fixed != kFixedA && !a.fixed()) a.x += a.inverse_mass * total.impulse, apply_angular_impulse(a, total.moment_a);
  if (fixed != kFixedB && !b.fixed()) b.x -= b.inverse_mass * total.impulse, apply_angular_impulse(b, -total.moment_b);
}

void BodyContacts::apply_velocities(RigidBody& a, RigidBody& b, double step, int fixed) const {
  const Sums total = sums(step);
  if (fixed != kFixedA) a.v += a.inverse_mass * total.impulse, a.omega += a.world_inverse_inertia(total.moment_a);
  if (fixed != kFixedB) b.v -= b.inverse_mass * total.impulse, b.omega -= b.world_inverse_inertia(total.moment_b);
}

void BodyContacts::solve_velocities(std::vector<RigidBody>& bodies) {
  for (const Active& pair : active_) {
    if (!(pair.lambda_n > 0.0)) continue;
    RigidBody &a = bodies[std::size_t(pair.a)], &b = bodies[std::size_t(pair.b)];
    const Body &body_a = bodies_[std::size_t(pair.a)], &body_b = bodies_[std::size_t(pair.b)];
    const double e_pair = std::max(body_a.restitution, body_b.restitution);
    const double mu_d = mixed(body_a.dynamic_friction, body_b.dynamic_friction);
    const Vec3d v_before_a = v_before_[std::size_t(pair.a)], omega_before_a = omega_before_[std::size_t(pair.a)];
    const Vec3d v_before_b = v_before_[std::size_t(pair.b)], omega_before_b = omega_before_[std::size_t(pair.b)];
    // Restitution: every touching point's normal speed change dv_j at once (the touches' "depth"),
    // with the best step, until none is off by more than kResolved (m/s).
    for (int pass = 0; pass < kNormalPasses; ++pass) {
      touches_.clear();
      double worst = 0.0;
      for (int s = pair.first_slot; s < pair.end_slot; ++s) {
        const Slot& slot = slots_[std::size_t(s)];
        if (!(slot.lambda_n > 0.0)) continue;
        const Vec3d n = slot.normal;
        const Vec3d r_a = rotate(a.q, slot.local_a), r_b = rotate(b.q, slot.local_b);
        const double v_n = dot(relative_velocity(a.v, a.omega, b.v, b.omega, r_a, r_b), n);
        const double before_n = dot(relative_velocity(v_before_a, omega_before_a, v_before_b, omega_before_b, r_a, r_b), n);
        const double e = std::fabs(before_n) > rest_speed_ ? e_pair : 0.0;
        const double dv = -v_n + std::max(-e * before_n, 0.0);
        const double w = pair_inverse_mass(a, b, r_a, r_b, n, pair.fixed);
        if (!(w > 0.0)) continue;
        touches_.push_back({s, r_a, r_b, n, dv, dv / w});
        worst = std::max(worst, std::fabs(dv));
      }
      if (!(worst > kResolved)) break;
      const double step = best_step(a, b, pair.fixed);
      if (!(step > 0.0)) break;
      apply_velocities(a, b, step, pair.fixed);
    }
    // Dynamic friction: each point's speed change along -v_t, min(mu_d lambda_n w_t / h, |v_t|),
    // at once, with the best step towards stopping every point's slip.
    if (!(mu_d > 0.0)) continue;
    touches_.clear();
    for (int s = pair.first_slot; s < pair.end_slot; ++s) {
      const Slot& slot = slots_[std::size_t(s)];
      if (!(slot.lambda_n > 0.0)) continue;
      const Vec3d n = slot.normal;
      const Vec3d r_a = rotate(a.q, slot.local_a), r_b = rotate(b.q, slot.local_b);
      const Vec3d v = relative_velocity(a.v, a.omega, b.v, b.omega, r_a, r_b);
      const Vec3d v_t = v - dot(v, n) * n;
      const double speed_t = length(v_t);
      if (!(speed_t > 0.0)) continue;
      const Vec3d against = -(1.0 / speed_t) * v_t;
      const double w_t = pair_inverse_mass(a, b, r_a, r_b, against, pair.fixed);
      if (!(w_t > 0.0)) continue;
      touches_.push_back({s, r_a, r_b, against, speed_t, std::min(mu_d * slot.lambda_n * w_t / h_, speed_t) / w_t});
    }
    if (touches_.empty()) continue;
    const double step = best_step(a, b, pair.fixed);
    apply_velocities(a, b, step, pair.fixed);
  }
}

}  // namespace seiche::rigid
