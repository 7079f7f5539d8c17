// Rigid bodies' contacts with the static world, friction and restitution (the math is in
// world_contacts.hpp).
#include "world_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "body_correction.hpp"
#include "body_solid.hpp"
#include "body_shape.hpp"
#include "body_surface.hpp"
#include "capsule_sides.hpp"

namespace seiche::rigid {

namespace {

// The normals' Jacobi passes stop where no point is deeper than this (m), or after this many.
// Each pass leaves of a face's common depth about 1 - n / (m w) (n points of generalized inverse
// mass w): 0.3 for a 0.2 x 0.1 x 0.2 box, so a few passes reach it.
constexpr double kResolved = 1e-12;
constexpr int kNormalPasses = 32;
// A body is tested point by point against the surfaces its bounding ball, grown by this factor,
// reaches (the ball of its extent holds every contact point's ball).
constexpr double kNearMargin = 1.5;

double mixed(double body, double surface) { return std::sqrt(body * surface); }

// Moves body point r (world frame, from the centre) by the velocity change dv there: the impulse
// p = dv / w, w along dv; v += p / m, omega += I^-1 (r x p).
void apply_velocity_change(RigidBody& b, Vec3d r, Vec3d dv) {
  const double size = length(dv);
  if (!(size > 0.0)) return;
  const Vec3d direction = (1.0 / size) * dv;
  const double w = positional_inverse_mass(b, r, direction);
  if (!(w > 0.0)) return;
  const Vec3d p = (size / w) * direction;
  b.v += b.inverse_mass * p;
  b.omega += b.world_inverse_inertia(cross(r, p));
}

}  // namespace

std::vector<ContactPoint> contact_points(const RigidBodyDef& def) {
  const ShapeDims d = body_shape_def(def);
  switch (d.shape) {
    case BodyShape::Sphere: return {{{}, d.radius}};
    case BodyShape::Capsule: return {{{0.0, -0.5 * d.length, 0.0}, d.radius}, {{0.0, 0.5 * d.length, 0.0}, d.radius}};
    case BodyShape::Box: break;
    case BodyShape::Mesh: {  // its vertices, like a box's corners (a face resting on a plane holds)
      std::vector<ContactPoint> vertices;
      for (const Vec3d& v : body_surface(def).vertices) vertices.push_back({v, 0.0});
      return vertices;
    }
  }
  std::vector<ContactPoint> corners;
  for (double sx : {-0.5, 0.5})
    for (double sy : {-0.5, 0.5})
      for (double sz : {-0.5, 0.5}) corners.push_back({{sx * d.size.x, sy * d.size.y, sz * d.size.z}, 0.0});
  return corners;
}

std::vector<ContactPoint> capsule_axis_points(const RigidBodyDef& def) {
  const ShapeDims d = body_shape_def(def);
  if (d.shape != BodyShape::Capsule || !(d.radius > 0.0)) return {};
  const int steps = int(std::ceil(d.length / d.radius));
  std::vector<ContactPoint> balls;
  for (int i = 1; i < steps; ++i) balls.push_back({{0.0, d.length * (double(i) / steps - 0.5), 0.0}, d.radius});
  return balls;
}

WorldContacts::WorldContacts(const SceneDef& scene, double substep,
                             std::span<const std::shared_ptr<const MeshSdf>> mesh_fields)
    : surfaces_(scene, mesh_fields), h_(substep) {
  const Vec3 g = scene.solver.gravity;
  rest_speed_ = 2.0 * std::hypot(double(g[0]), double(g[1]), double(g[2])) * h_;
  for (const RigidBodyDef& def : scene.rigid_bodies) {
    first_point_.push_back(int(points_.size()));
    for (const ContactPoint& p : contact_points(def)) points_.push_back(p);
    // A capsule's side: its axis balls against the mesh colliders, one point per role
    // (capsule_sides.hpp, no ball) against the box colliders.
    first_axis_point_.push_back(int(points_.size()));
    for (const ContactPoint& p : capsule_axis_points(def)) points_.push_back(p);
    const ShapeDims dims = body_shape_def(def);
    const bool capsule = dims.shape == BodyShape::Capsule;
    first_side_point_.push_back(capsule ? int(points_.size()) : -1);
    capsule_solid_.push_back(capsule ? body_solid(dims, nullptr) : SolidSurface{});
    if (capsule) points_.resize(points_.size() + kCapsuleSideRoles);
    materials_.push_back({def.friction, def.dynamic_friction, def.restitution});
    extent_.push_back(mass_properties(dims).extent);
  }
  first_point_.push_back(int(points_.size()));
  for (int s = 0; s < surfaces_.count(); ++s) {
    const SolidSurface& world = surfaces_.solid(s);
    ColliderFrame collider;
    if (world.shape == ColliderDef::Shape::Box || world.shape == ColliderDef::Shape::Capsule ||
        world.shape == ColliderDef::Shape::Sphere) {
      collider.frame.x = world.shape == ColliderDef::Shape::Sphere ? world.a : 0.5 * (world.a + world.b);
      collider.solid = world;
      collider.solid.a = world.a - collider.frame.x;
      if (world.shape != ColliderDef::Shape::Sphere) collider.solid.b = world.b - collider.frame.x;
    }
    collider_frames_.push_back(collider);
  }
  slots_.resize(points_.size() * std::size_t(surfaces_.count()));
  pairs_.resize(scene.rigid_bodies.size() * std::size_t(surfaces_.count()));
  v_before_.resize(scene.rigid_bodies.size());
  omega_before_.resize(scene.rigid_bodies.size());
  near_.resize(std::size_t(surfaces_.count()));
}

void WorldContacts::begin_substep(const std::vector<RigidBody>& bodies) {
  for (std::size_t k = 0; k < bodies.size(); ++k) v_before_[k] = bodies[k].v, omega_before_[k] = bodies[k].omega;
  std::fill(slots_.begin(), slots_.end(), Slot{});
  std::fill(pairs_.begin(), pairs_.end(), Pair{});
}

void WorldContacts::solve_positions(std::vector<RigidBody>& bodies) {
  const int surfaces = surfaces_.count();
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    RigidBody& b = bodies[k];
    if (b.fixed()) continue;
    // The normals: every point against every surface, all from the same pose (Jacobi), then
    // applied together; again until no point is deeper than kResolved (or kNormalPasses).
    for (int point = first_point_[k]; point < first_point_[k + 1]; ++point)
      for (int s = 0; s < surfaces; ++s) slot(point, s).touching = false;
    // Only the surfaces the body's bounding ball reaches (grown by a margin for the passes' moves).
    bool touches_any = false;
    for (int s = 0; s < surfaces; ++s) {
      SurfacePenetration pen;
      near_[std::size_t(s)] = surfaces_.penetration(s, b.x, kNearMargin * extent_[k], pen);
      touches_any = touches_any || near_[std::size_t(s)];
    }
    if (!touches_any) continue;
    for (int pass = 0; pass < kNormalPasses; ++pass) {
      const RigidBody before = b;
      double deepest = 0.0;
      // Each touching point: its slot (point, s), body point `local` (body frame), depth, normal n.
      touches_.clear();
      bool sides = false;
      const auto touch = [&](int point, int s, Vec3d local, Vec3d n, double depth) {
        const Vec3d r = rotate(before.q, local);
        const double w = positional_inverse_mass(before, r, n);
        Slot& contact = slot(point, s);
        contact.normal = n;
        contact.local = local;
        if (w > 0.0) touches_.push_back({point, s, r, n, depth, depth / w});
      };
      const int first_side = first_side_point_[k];
      const int balls_end = first_side >= 0 ? first_side : first_point_[k + 1];
      for (int point = first_point_[k]; point < balls_end; ++point) {
        const ContactPoint& c = points_[std::size_t(point)];
        const bool on_axis = point >= first_axis_point_[k];  // a capsule's axis ball: meshes only
        for (int s = 0; s < surfaces; ++s) {
          SurfacePenetration pen;
          if (!near_[std::size_t(s)] || (on_axis && surfaces_.solid(s).shape != ColliderDef::Shape::Mesh) ||
              !surfaces_.penetration(s, before.world_point(c.centre), c.radius, pen))
            continue;
          touch(point, s, c.centre - c.radius * rotate_back(before.q, pen.normal), pen.normal, pen.depth);
        }
      }
      // A capsule's side against the box, sphere and capsule colliders (capsule_sides.hpp; against
      // a mesh its axis balls above; against the domain's walls and a plane its cap balls are the
      // deepest points).
      for (int s = 0; first_side >= 0 && s < surfaces; ++s) {
        const ColliderDef::Shape shape = surfaces_.solid(s).shape;
        if (!near_[std::size_t(s)] || (shape != ColliderDef::Shape::Box && shape != ColliderDef::Shape::Sphere &&
                                       shape != ColliderDef::Shape::Capsule))
          continue;
        const ColliderFrame& collider = collider_frames_[std::size_t(s)];
        BoxBoxContact found[kCapsuleSideRoles];
        if (shape == ColliderDef::Shape::Box)
          capsule_side_contacts(before, capsule_solid_[k], collider.frame, collider.solid, found);
        else
          capsule_round_collider_contacts(before, capsule_solid_[k], collider.frame, collider.solid, found);
        for (int role = 0; role < kCapsuleSideRoles; ++role) {
          if (!(found[role].depth > 0.0)) continue;
          sides = true;
          touch(first_side + role, s, rotate_back(before.q, found[role].point_a - before.x), found[role].normal,
                found[role].depth);
        }
      }
      const double step = sides ? best_step(before) : 1.0;
      for (const Touch& t : touches_) {
        const double dlambda_n = step * t.dlambda;
        Slot& contact = slot(t.point, t.surface);
        contact.lambda_n += dlambda_n;
        contact.touching = true;
        body_surface(k, t.surface).lambda_n += dlambda_n;
        apply_positional_impulse(b, t.r, dlambda_n * t.normal);
        deepest = std::max(deepest, t.depth);
      }
      if (!(deepest > kResolved)) break;
    }
    // Static friction, per surface, within the cone of the body and that surface together.
    for (int s = 0; s < surfaces; ++s) {
      Pair& pair = body_surface(k, s);
      const double mu_s = mixed(materials_[k].static_friction, surfaces_.friction(s));
      if (!(mu_s > 0.0) || !(pair.lambda_n > 0.0)) continue;
      const RigidBody after_normals = b;
      // The slip of body point `local` since the substep began, along the surface.
      const auto slip_of = [&](Vec3d local, Vec3d n) {
        const Vec3d moved = after_normals.world_point(local) - (after_normals.x_prev + rotate(after_normals.q_prev, local));
        return moved - dot(moved, n) * n;
      };
      // A face on the surface (3 points or more) cannot tip: its normals hold it. Its friction is
      // one constraint at the points' centre (weighted by their normal multipliers), which moves
      // the body along the surface and turns it about the normal only.
      Patch patch;
      if (face_patch(k, s, true, patch)) {
        const Vec3d n = patch.normal;
        const Vec3d r = rotate(after_normals.q, patch.centre);
        const Vec3d tangential = slip_of(patch.centre, n);
        const double slip = length(tangential);
        const Vec3d t = slip > 0.0 ? (1.0 / slip) * tangential : Vec3d{};
        const Vec3d impulse = slip > 0.0 ? -(slip / patch_inverse_mass(after_normals, r, t, n)) * t : Vec3d{};
        if (slip > 0.0 && length(pair.lambda_t + impulse) < mu_s * pair.lambda_n) {
          pair.lambda_t += impulse;
          b.x += b.inverse_mass * impulse;
          b.q = rotate_by_small(b.q, (dot(cross(r, impulse), n) * angular_inverse_mass(after_normals, n)) * n);
        }
        // Its turn about the normal since the substep began, undone where the torque stays within
        // what the points' friction holds at their distance from the centre: mu_s lambda_n rho.
        const double turn = dot(rotation_vector(b.q * conjugate(b.q_prev)), n);
        const double w_n = angular_inverse_mass(b, n);
        if (!(w_n > 0.0)) continue;
        const double twist = -turn / w_n;
        if (std::fabs(pair.twist + twist) < mu_s * pair.lambda_n * patch.radius) {
          pair.twist += twist;
          apply_angular_impulse(b, twist * n);
        }
        continue;
      }
      // Else every touching point's impulse from the same pose (Jacobi), applied together.
      Vec3d sum{};
      friction_.clear();
      for (int point = first_point_[k]; point < first_point_[k + 1]; ++point) {
        const Slot& contact = slot(point, s);
        if (!contact.touching) continue;
        const Vec3d r = rotate(after_normals.q, contact.local);
        const Vec3d tangential = slip_of(contact.local, contact.normal);
        const double slip = length(tangential);
        if (!(slip > 0.0)) continue;
        const Vec3d t = (1.0 / slip) * tangential;
        const double w_t = positional_inverse_mass(after_normals, r, t);
        if (!(w_t > 0.0)) continue;
        const Vec3d impulse = -(slip / w_t) * t;
        friction_.push_back({r, impulse});
        sum += impulse;
      }
      if (friction_.empty() || !(length(pair.lambda_t + sum) < mu_s * pair.lambda_n)) continue;  // slides
      pair.lambda_t += sum;
      for (const auto& [r, impulse] : friction_) apply_positional_impulse(b, r, impulse);
    }
  }
}

void WorldContacts::solve_velocities(std::vector<RigidBody>& bodies) {
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    RigidBody& b = bodies[k];
    if (b.fixed()) continue;
    const Material& material = materials_[k];
    for (int s = 0; s < surfaces_.count(); ++s) {
      if (!(body_surface(k, s).lambda_n > 0.0)) continue;
      // Restitution, point by point.
      for (int point = first_point_[k]; point < first_point_[k + 1]; ++point) {
        const Slot& contact = slot(point, s);
        if (!(contact.lambda_n > 0.0)) continue;
        const Vec3d n = contact.normal;
        const Vec3d r = rotate(b.q, contact.local);
        const double v_n = dot(b.v + cross(b.omega, r), n);
        const double before_n = dot(v_before_[k] + cross(omega_before_[k], r), n);
        const double e = std::fabs(before_n) > rest_speed_ ? material.restitution : 0.0;
        apply_velocity_change(b, r, (-v_n + std::max(-e * before_n, 0.0)) * n);
      }
      // Dynamic friction: a face as one patch, else point by point.
      const double mu_d = mixed(material.dynamic_friction, surfaces_.friction(s));
      if (!(mu_d > 0.0)) continue;
      Patch patch;
      if (face_patch(k, s, false, patch)) {
        const Vec3d n = patch.normal;
        const double lambda_n = body_surface(k, s).lambda_n;
        const Vec3d r = rotate(b.q, patch.centre);
        const Vec3d v = b.v + cross(b.omega, r);
        const Vec3d v_t = v - dot(v, n) * n;
        const double speed_t = length(v_t);
        if (speed_t > 0.0) {
          const double w_t = patch_inverse_mass(b, r, (1.0 / speed_t) * v_t, n);
          const double dv = std::min(mu_d * lambda_n * w_t / h_, speed_t);
          const Vec3d p = (-dv / (speed_t * w_t)) * v_t;
          b.v += b.inverse_mass * p;
          b.omega += (dot(cross(r, p), n) * angular_inverse_mass(b, n)) * n;
        }
        // Its spin about the normal, slowed by the torque mu_d lambda_n rho / h.
        const double spin = dot(b.omega, n), w_n = angular_inverse_mass(b, n);
        if (spin != 0.0 && w_n > 0.0) {
          const double slowed = std::min(mu_d * lambda_n * patch.radius * w_n / h_, std::fabs(spin));
          b.omega += b.world_inverse_inertia((-std::copysign(slowed, spin) / w_n) * n);
        }
        continue;
      }
      for (int point = first_point_[k]; point < first_point_[k + 1]; ++point) {
        const Slot& contact = slot(point, s);
        if (!(contact.lambda_n > 0.0)) continue;
        const Vec3d n = contact.normal;
        const Vec3d r = rotate(b.q, contact.local);
        const Vec3d v = b.v + cross(b.omega, r);
        const Vec3d v_t = v - dot(v, n) * n;
        const double speed_t = length(v_t);
        if (!(speed_t > 0.0)) continue;
        const double w_t = positional_inverse_mass(b, r, (1.0 / speed_t) * v_t);
        apply_velocity_change(b, r, -(std::min(mu_d * contact.lambda_n * w_t / h_, speed_t) / speed_t) * v_t);
      }
    }
  }
}

double WorldContacts::best_step(const RigidBody& b) const {
  // The body's move under all the impulses together: dx = sum p / m, dtheta = I^-1 sum r x p.
  Vec3d impulse{}, moment{};
  for (const Touch& t : touches_) impulse += t.dlambda * t.normal, moment += cross(t.r, t.dlambda * t.normal);
  const Vec3d dx = b.inverse_mass * impulse, dtheta = b.world_inverse_inertia(moment);
  // Each point's depth change dd_j = n_j.(dx + dtheta x r_j); s = sum d_j dd_j / sum dd_j^2.
  double fit = 0.0, size = 0.0;
  for (const Touch& t : touches_) {
    const double change = dot(t.normal, dx + cross(dtheta, t.r));
    fit += t.depth * change, size += change * change;
  }
  return size > 0.0 ? std::clamp(fit / size, 0.0, 1.0) : 1.0;
}

void WorldContacts::held_up(std::vector<char>& out, Vec3d up, double min_cosine) const {
  const std::size_t bodies = materials_.size(), surfaces = std::size_t(surfaces_.count());
  out.assign(bodies, 0);
  for (std::size_t k = 0; k < bodies; ++k)
    for (std::size_t s = 0; s < surfaces && !out[k]; ++s) {
      if (!(pairs_[k * surfaces + s].lambda_n > 0.0)) continue;
      for (int point = first_point_[k]; point < first_point_[k + 1] && !out[k]; ++point) {
        const Slot& contact = slots_[std::size_t(point) * surfaces + s];
        out[k] = contact.lambda_n > 0.0 && dot(contact.normal, up) > min_cosine;
      }
    }
}

bool WorldContacts::face_patch(std::size_t body, int surface, bool this_iteration, Patch& out) {
  Vec3d centre{};
  double weight = 0.0;
  int count = 0;
  for (int point = first_point_[body]; point < first_point_[body + 1]; ++point) {
    const Slot& contact = slot(point, surface);
    if (this_iteration ? !contact.touching : !(contact.lambda_n > 0.0)) continue;
    ++count;
    centre += contact.lambda_n * contact.local;
    weight += contact.lambda_n;
    out.normal = contact.normal;
  }
  if (count < 3 || !(weight > 0.0)) return false;
  out.centre = (1.0 / weight) * centre;
  double spread = 0.0;
  for (int point = first_point_[body]; point < first_point_[body + 1]; ++point) {
    const Slot& contact = slot(point, surface);
    if (this_iteration ? !contact.touching : !(contact.lambda_n > 0.0)) continue;
    spread += contact.lambda_n * length(contact.local - out.centre);
  }
  out.radius = spread / weight;
  return true;
}

}  // namespace seiche::rigid
