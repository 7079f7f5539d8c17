// Particle-shape collisions (the math is in collisions.hpp): for every free particle, each
// collider of the scene, then the domain box (last: the domain always wins).
//
// Colliders (plane, box, sphere, capsule, SDF) run per particle in scalar code, and only when
// the scene has colliders. The domain runs lane = particle over kLanes consecutive particles
// (their radii one load from the radius column): for each axis a in turn, the wall a particle
// is past (p_a < lo_a, or p_a > hi_a, with lo and hi the domain shrunk by the particle's
// radius) has normal n = +-e_a and depth d; then
//   p += d n,  friction on dx = p - x (as in collisions.hpp),  p_a = lo_a (hi_a) exactly.
// Every branch of the scalar formulas is a select here and the arithmetic is the same operations
// in the same order, so each particle gets the bits a scalar loop gives (kernel_tests.cpp checks
// this against a scalar reference); a batch with no particle past a wall only compares.
#include "seiche/kernels/collisions.hpp"

#include <algorithm>
#include <cmath>

#include "simd.hpp"

namespace seiche::kernels {

namespace {

using simd::Floats;
using simd::kLanes;
using simd::Mask;
using simd::Lanes;
constexpr std::size_t kBatchesPerTask = 512;  // 4,096 particles with 8 lanes

// ---- Colliders: scalar, per particle ------------------------------------------------------------

struct Point {
  float x, y, z;
};

// Push p out by depth along unit normal n, then apply friction to the substep's motion.
inline void resolve_contact(Point& p, const Point& x, const float n[3], float depth, float mu) {
  p.x += depth * n[0];
  p.y += depth * n[1];
  p.z += depth * n[2];
  if (mu <= 0.0f) return;
  const float dx = p.x - x.x, dy = p.y - x.y, dz = p.z - x.z;
  const float dn = dx * n[0] + dy * n[1] + dz * n[2];
  const float tx = dx - dn * n[0], ty = dy - dn * n[1], tz = dz - dn * n[2];
  const float t_len = std::sqrt(tx * tx + ty * ty + tz * tz);
  if (t_len <= 0.0f) return;
  const float keep = t_len <= mu * depth ? 1.0f : mu * depth / t_len;
  p.x -= keep * tx;
  p.y -= keep * ty;
  p.z -= keep * tz;
}

// Out of the ball of radius `reach` around c, along the line from c (up where p is at c).
inline void push_out_of_ball(Point& p, const Point& x, const float c[3], float reach, float mu) {
  const float dx = p.x - c[0], dy = p.y - c[1], dz = p.z - c[2];
  const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
  const float depth = reach - len;
  if (depth <= 0.0f) return;
  float n[3] = {0.0f, 1.0f, 0.0f};
  if (len > 1e-12f) n[0] = dx / len, n[1] = dy / len, n[2] = dz / len;
  resolve_contact(p, x, n, depth, mu);
}

inline void collide_shape(Point& p, const Point& x, const CollisionShape& s, float r) {
  switch (s.kind) {
    case CollisionShape::Kind::Plane: {
      const float d =
          (p.x - s.a[0]) * s.b[0] + (p.y - s.a[1]) * s.b[1] + (p.z - s.a[2]) * s.b[2] - r;
      if (d < 0.0f) resolve_contact(p, x, s.b, -d, s.friction);
      break;
    }
    case CollisionShape::Kind::Sphere:
      push_out_of_ball(p, x, s.a, s.radius + r, s.friction);
      break;
    case CollisionShape::Kind::Capsule: {
      // Closest point on the segment a-b, then as a sphere around it (a zero-length segment is
      // a sphere around a).
      const float ab[3] = {s.b[0] - s.a[0], s.b[1] - s.a[1], s.b[2] - s.a[2]};
      const float ab2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
      float t = 0.0f;
      if (ab2 > 1e-24f) {
        t = ((p.x - s.a[0]) * ab[0] + (p.y - s.a[1]) * ab[1] + (p.z - s.a[2]) * ab[2]) / ab2;
        t = std::clamp(t, 0.0f, 1.0f);
      }
      const float closest[3] = {s.a[0] + t * ab[0], s.a[1] + t * ab[1], s.a[2] + t * ab[2]};
      push_out_of_ball(p, x, closest, s.radius + r, s.friction);
      break;
    }
    case CollisionShape::Kind::Sdf: {
      // Outside the sampled box the field knows nothing: no contact.
      float distance = 0.0f, n[3];
      if (s.sdf == nullptr || !s.sdf->sample(p.x, p.y, p.z, distance, n)) break;
      if (distance < r) resolve_contact(p, x, n, r - distance, s.friction);
      break;
    }
    case CollisionShape::Kind::Box: {
      // Inside the box grown by r: leave through the nearest face.
      const float pc[3] = {p.x, p.y, p.z};
      float best = INFINITY;
      int best_axis = -1;
      float best_sign = 0.0f;
      for (int axis = 0; axis < 3; ++axis) {
        const float to_min = pc[axis] - (s.a[axis] - r);
        const float to_max = (s.b[axis] + r) - pc[axis];
        if (to_min <= 0.0f || to_max <= 0.0f) return;  // outside on this axis
        if (to_min < best) best = to_min, best_axis = axis, best_sign = -1.0f;
        if (to_max < best) best = to_max, best_axis = axis, best_sign = 1.0f;
      }
      float n[3] = {0, 0, 0};
      n[best_axis] = best_sign;
      resolve_contact(p, x, n, best, s.friction);
      break;
    }
  }
}

void collide_shapes(const ParticleView& p, std::span<const CollisionShape> shapes, std::size_t begin,
                    std::size_t end) {
  for (std::size_t i = begin; i != end; ++i) {
    if (p.w[i] <= 0.0f) continue;
    const float r = p.radius[i];
    Point q{p.px[i], p.py[i], p.pz[i]};
    const Point x{p.x[i], p.y[i], p.z[i]};
    for (const CollisionShape& s : shapes) collide_shape(q, x, s, r);
    p.px[i] = q.x, p.py[i] = q.y, p.pz[i] = q.z;
  }
}

// ---- The domain: lane = particle ----------------------------------------------------------------

// The walls of axis a for every lane where `movable`: resolve_contact with n = +-e_a, as selects.
SEICHE_INLINE inline void domain_axis(Floats p[3], const Floats x[3], int a, const Floats& lo,
                                      const Floats& hi, float mu, const Mask& movable) {
  const Floats v = p[a];
  const Mask below = movable && (v < lo);
  const Mask above = movable && (v > hi);  // never with below: hi >= lo (NaN: neither)
  const Mask contact = below || above;
  if (!xsimd::any(contact)) return;
  const Floats depth = xsimd::select(below, lo - v, v - hi);
  Floats n[3] = {Floats(0.0f), Floats(0.0f), Floats(0.0f)};
  n[a] = xsimd::select(below, Floats(1.0f), Floats(-1.0f));
  Floats q[3];
  for (int k = 0; k < 3; ++k) q[k] = p[k] + depth * n[k];
  if (!(mu <= 0.0f)) {
    const Floats d[3] = {q[0] - x[0], q[1] - x[1], q[2] - x[2]};
    const Floats dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
    const Floats t[3] = {d[0] - dn * n[0], d[1] - dn * n[1], d[2] - dn * n[2]};
    const Floats t_len = xsimd::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    const Floats bound = Floats(mu) * depth;
    const Floats keep = xsimd::select(t_len <= bound, Floats(1.0f), bound / t_len);
    const Mask sticks = t_len <= Floats(0.0f);  // nothing to remove
    for (int k = 0; k < 3; ++k) q[k] = xsimd::select(sticks, q[k], q[k] - keep * t[k]);
  }
  q[a] = xsimd::select(below, lo, hi);  // exact, whatever rounding the push did
  for (int k = 0; k < 3; ++k) p[k] = xsimd::select(contact, q[k], p[k]);
}

SEICHE_INLINE inline void collide_domain(const ParticleView& v, const CollisionParams& c,
                                         const Lanes& lanes) {
  Floats p[3] = {lanes.load(v.px), lanes.load(v.py), lanes.load(v.pz)};
  const Floats x[3] = {lanes.load(v.x), lanes.load(v.y), lanes.load(v.z)};
  const Mask movable = !(lanes.load(v.w) <= Floats(0.0f));  // as the scalar `w <= 0: skip`
  const Floats r = lanes.load(v.radius);
  for (int a = 0; a < 3; ++a) {
    const Floats lo = Floats(c.domain_min[a]) + r;
    const Floats shrunk = Floats(c.domain_max[a]) - r;
    const Floats hi = xsimd::select(shrunk < lo, lo, shrunk);  // std::max(shrunk, lo)
    domain_axis(p, x, a, lo, hi, c.domain_friction, movable);
  }
  lanes.store(v.px, p[0]), lanes.store(v.py, p[1]), lanes.store(v.pz, p[2]);
}

}  // namespace

void solve_collisions(const ParticleView& p, const CollisionParams& params,
                      std::span<const CollisionShape> shapes) {
  simd::parallel_batches(0, p.n, kBatchesPerTask, [&](std::size_t begin, std::size_t end) {
    if (!shapes.empty()) collide_shapes(p, shapes, begin, end);
    for (std::size_t i = begin; i < end; i += kLanes)
      collide_domain(p, params, Lanes{i, std::min(kLanes, end - i)});
  });
}

}  // namespace seiche::kernels
