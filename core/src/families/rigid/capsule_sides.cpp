// The contacts of a capsule's side with a capsule or a box, and with a sphere or capsule collider
// (the math is in capsule_sides.hpp).
#include "capsule_sides.hpp"

#include <algorithm>
#include <cmath>

namespace seiche::rigid {

namespace {

using Shape = ColliderDef::Shape;

constexpr int kFirst = 0, kLast = 1, kDeepest = 2;  // the roles t_0, t_1, t*
// Segments whose directions' sine squared is below this are parallel.
constexpr double kParallel = 1e-12;
// The ternary search's steps: each keeps 2/3 of the bracket, (2/3)^64 = 5e-12 of the segment.
constexpr int kSearchSteps = 64;

double component(Vec3d v, int k) { return k == 0 ? v.x : k == 1 ? v.y : v.z; }

// The signed distance of p from the box [-h, h]: |max(q, 0)| + min(max_k q_k, 0), q = |p| - h.
double box_distance(Vec3d p, Vec3d h) {
  const Vec3d q{std::fabs(p.x) - h.x, std::fabs(p.y) - h.y, std::fabs(p.z) - h.z};
  const Vec3d out{std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0)};
  return length(out) + std::min(std::max({q.x, q.y, q.z}), 0.0);
}

// A's ball of radius rho centred at `centre` (world) into B's solid: the contact as the balls'
// (body_contacts.hpp), with a the capsule where capsule_is_a. False where it does not reach.
bool ball_contact(Vec3d centre, double rho, const RigidBody& other, const SolidSurface& other_solid, bool capsule_is_a,
                  BoxBoxContact& out) {
  SurfacePenetration pen;
  if (!penetration(other_solid, rotate_back(other.q, centre - other.x), rho, pen)) return false;
  const Vec3d m = rotate(other.q, pen.normal);  // out of the other body
  const Vec3d own_point = centre - rho * m, other_point = own_point + pen.depth * m;
  out.point_a = capsule_is_a ? own_point : other_point;
  out.point_b = capsule_is_a ? other_point : own_point;
  out.normal = capsule_is_a ? m : -m;
  out.depth = pen.depth;
  return true;
}

void capsules_crossed(const RigidBody& a, const SolidSurface& sa, const RigidBody& b, const SolidSurface& sb,
                      BoxBoxContact& out) {
  const Vec3d p_a = a.world_point(sa.a), d_a = a.world_point(sa.b) - p_a;
  const Vec3d p_b = b.world_point(sb.a), d_b = b.world_point(sb.b) - p_b;
  const Vec3d r = p_a - p_b;
  const double aa = dot(d_a, d_a), bb = dot(d_b, d_b), ab = dot(d_a, d_b), ar = dot(d_a, r), br = dot(d_b, r);
  const double denominator = aa * bb - ab * ab;
  if (!(denominator > kParallel * aa * bb)) return;  // parallel: an end's ball
  const double s = (ab * br - bb * ar) / denominator, t = (aa * br - ab * ar) / denominator;
  if (!(s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0)) return;  // an end is closest: its ball
  const Vec3d c_a = p_a + s * d_a, c_b = p_b + t * d_b, apart = c_a - c_b;
  const double distance = length(apart), depth = sa.radius + sb.radius - distance;
  if (!(depth > 0.0)) return;
  Vec3d n = distance > 1e-12 ? (1.0 / distance) * apart : normalized_or_zero(cross(d_a, d_b));
  if (distance <= 1e-12 && dot(n, a.x - b.x) < 0.0) n = -n;
  if (!(dot(n, n) > 0.5)) return;
  out.point_a = c_a - sa.radius * n, out.point_b = c_b + sb.radius * n;
  out.normal = n, out.depth = depth;
}

void capsule_on_box(const RigidBody& capsule, const SolidSurface& cs, const RigidBody& box, const SolidSurface& bs,
                    bool capsule_is_a, BoxBoxContact (&out)[kCapsuleSideRoles]) {
  // The segment in the box's frame.
  const Vec3d from = rotate_back(box.q, capsule.world_point(cs.a) - box.x);
  const Vec3d along = rotate_back(box.q, capsule.world_point(cs.b) - box.x) - from;
  const Vec3d half = 0.5 * (bs.b - bs.a);
  // Both ends beyond one face of the box grown by the radius: the whole segment is (no search).
  const Vec3d to = from + along;
  for (int k = 0; k < 3; ++k) {
    const double reach = component(half, k) + cs.radius;
    if (std::min(component(from, k), component(to, k)) > reach || std::max(component(from, k), component(to, k)) < -reach)
      return;
  }
  const auto f = [&](double t) { return box_distance(from + t * along, half); };
  double lo = 0.0, hi = 1.0;
  for (int step = 0; step < kSearchSteps; ++step) {
    const double m1 = lo + (hi - lo) / 3.0, m2 = hi - (hi - lo) / 3.0;
    if (f(m1) <= f(m2)) hi = m2;
    else lo = m1;
  }
  const double deepest = 0.5 * (lo + hi), f_deepest = f(deepest);
  if (!(f_deepest < cs.radius)) return;  // the side reaches nowhere into the box
  // The face: the axis where the deepest point sticks out most; the segment clipped to its sides.
  const Vec3d p = from + deepest * along;
  int face = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(component(p, k)) - component(half, k) > std::fabs(component(p, face)) - component(half, face)) face = k;
  double t0 = 0.0, t1 = 1.0;
  for (int j = 0; j < 3 && t0 <= t1; ++j) {
    if (j == face) continue;
    const double start = component(from, j), rate = component(along, j), limit = component(half, j);
    if (std::fabs(rate) > 1e-15) {
      const double enter = (-limit - start) / rate, leave = (limit - start) / rate;
      t0 = std::max(t0, std::min(enter, leave)), t1 = std::min(t1, std::max(enter, leave));
    } else if (std::fabs(start) > limit) {
      t1 = -1.0;  // beside the face all along
    }
  }
  const auto at = [&](double t) { return capsule.world_point(cs.a) + t * (capsule.world_point(cs.b) - capsule.world_point(cs.a)); };
  if (t0 <= t1) {
    if (t0 > 0.0 && t0 < 1.0) ball_contact(at(t0), cs.radius, box, bs, capsule_is_a, out[kFirst]);
    if (t1 > t0 && t1 > 0.0 && t1 < 1.0) ball_contact(at(t1), cs.radius, box, bs, capsule_is_a, out[kLast]);
  }
  if (f_deepest < f(0.0) && f_deepest < f(1.0)) ball_contact(at(deepest), cs.radius, box, bs, capsule_is_a, out[kDeepest]);
}

// How many of the roles' contacts touch (depth > 0).
int touching(const BoxBoxContact (&out)[kCapsuleSideRoles]) {
  return int(std::count_if(std::begin(out), std::end(out), [](const BoxBoxContact& c) { return c.depth > 0.0; }));
}

// The capsule's ball at its segment's point closest to `target` (world) against the collider,
// in `role`, where that point lies strictly inside the segment (else its cap ball is the contact).
void ball_closest_to(Vec3d target, const RigidBody& capsule, const SolidSurface& cs, const RigidBody& frame,
                     const SolidSurface& round, BoxBoxContact& out) {
  const Vec3d from = capsule.world_point(cs.a), along = capsule.world_point(cs.b) - from;
  const double length_squared = dot(along, along);
  if (!(length_squared > 0.0)) return;
  const double t = dot(target - from, along) / length_squared;
  if (t > 0.0 && t < 1.0) ball_contact(from + t * along, cs.radius, frame, round, true, out);
}

}  // namespace

int capsule_round_collider_contacts(const RigidBody& capsule, const SolidSurface& capsule_solid, const RigidBody& frame,
                                    const SolidSurface& round, BoxBoxContact (&out)[kCapsuleSideRoles]) {
  for (BoxBoxContact& c : out) c = BoxBoxContact{};
  if (round.shape == Shape::Sphere) {
    ball_closest_to(frame.world_point(round.a), capsule, capsule_solid, frame, round, out[kDeepest]);
  } else if (round.shape == Shape::Capsule) {
    capsules_crossed(capsule, capsule_solid, frame, round, out[kDeepest]);
    if (!(out[kDeepest].depth > 0.0)) {  // not crossed inside both: the collider's ends
      ball_closest_to(frame.world_point(round.a), capsule, capsule_solid, frame, round, out[kFirst]);
      ball_closest_to(frame.world_point(round.b), capsule, capsule_solid, frame, round, out[kLast]);
    }
  }
  return touching(out);
}

bool has_capsule_sides(const SolidSurface& a, const SolidSurface& b) {
  return (a.shape == Shape::Capsule && (b.shape == Shape::Capsule || b.shape == Shape::Box)) ||
         (b.shape == Shape::Capsule && a.shape == Shape::Box);
}

int capsule_side_contacts(const RigidBody& a, const SolidSurface& solid_a, const RigidBody& b,
                          const SolidSurface& solid_b, BoxBoxContact (&out)[kCapsuleSideRoles]) {
  for (BoxBoxContact& c : out) c = BoxBoxContact{};
  if (solid_a.shape == Shape::Capsule && solid_b.shape == Shape::Capsule)
    capsules_crossed(a, solid_a, b, solid_b, out[kDeepest]);
  else if (solid_a.shape == Shape::Capsule && solid_b.shape == Shape::Box)
    capsule_on_box(a, solid_a, b, solid_b, true, out);
  else if (solid_b.shape == Shape::Capsule && solid_a.shape == Shape::Box)
    capsule_on_box(b, solid_b, a, solid_a, false, out);
  return touching(out);
}

}  // namespace seiche::rigid
