#include "seiche/kernels/collisions.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "seiche/kernels/phase.hpp"

namespace seiche::kernels {

namespace {

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

inline void collide_domain(Point& p, const Point& x, const CollisionParams& c, float r) {
  float* pc[3] = {&p.x, &p.y, &p.z};
  for (int axis = 0; axis < 3; ++axis) {
    const float lo = c.domain_min[axis] + r;
    const float hi = std::max(c.domain_max[axis] - r, lo);
    float n[3] = {0, 0, 0};
    const float v = *pc[axis];
    if (v < lo) {
      n[axis] = 1.0f;
      resolve_contact(p, x, n, lo - v, c.domain_friction);
      *pc[axis] = lo;  // exact, whatever rounding the push did
    } else if (v > hi) {
      n[axis] = -1.0f;
      resolve_contact(p, x, n, v - hi, c.domain_friction);
      *pc[axis] = hi;
    }  // a NaN fails both tests and stays NaN: the run's finite check must see it, not a wall
  }
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

// A particle's collision radius: fluid_radius for fluid, its cloth's half thickness for cloth.
inline float particle_radius(std::uint32_t phase, const CollisionParams& c) {
  switch (phase_material(phase)) {
    case Material::Fluid:
      return c.fluid_radius;
    case Material::Cloth:
      return c.cloth_radius != nullptr ? c.cloth_radius[phase >> 8] : 0.0f;
    default:
      return 0.0f;
  }
}

}  // namespace

void solve_collisions(const ParticleView& p, const CollisionParams& params,
                      std::span<const CollisionShape> shapes) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.n, 2048), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      if (p.w[i] <= 0.0f) continue;
      const float r = particle_radius(p.phase[i], params);
      Point q{p.px[i], p.py[i], p.pz[i]};
      const Point x{p.x[i], p.y[i], p.z[i]};
      for (const CollisionShape& s : shapes) collide_shape(q, x, s, r);
      collide_domain(q, x, params, r);  // last: the domain always wins
      p.px[i] = q.x;
      p.py[i] = q.y;
      p.pz[i] = q.z;
    }
  });
}

}  // namespace seiche::kernels
