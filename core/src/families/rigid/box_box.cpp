// The contact of two boxes by separating axes and clipping (the math is in box_box.hpp).
#include "box_box.hpp"

#include <cmath>
#include <initializer_list>

namespace seiche::rigid {

namespace {

// The reference face's side planes are moved out by this share of its half size: an incident edge
// that lies on a side (equal boxes stacked) stays in when rounding puts it a few ulps out.
constexpr double kClipSlack = 1e-9;

struct OrientedBox {
  Vec3d centre;
  Vec3d axes[3];
  double half[3];
};

OrientedBox oriented(const RigidBody& body, Vec3d half) {
  return {body.x,
          {rotate(body.q, {1.0, 0.0, 0.0}), rotate(body.q, {0.0, 1.0, 0.0}), rotate(body.q, {0.0, 0.0, 1.0})},
          {half.x, half.y, half.z}};
}

// sum_i h_i |u.axis_i|: how far the box reaches from its centre along unit u.
double support(const OrientedBox& box, Vec3d u) {
  return box.half[0] * std::fabs(dot(u, box.axes[0])) + box.half[1] * std::fabs(dot(u, box.axes[1])) +
         box.half[2] * std::fabs(dot(u, box.axes[2]));
}

// The part of the polygon in[0..n) where p.u <= limit (Sutherland-Hodgman, one plane).
int clip(const Vec3d* in, int n, Vec3d u, double limit, Vec3d* out) {
  int m = 0;
  for (int k = 0; k < n; ++k) {
    const Vec3d p = in[k], q = in[(k + 1) % n];
    const double dp = dot(p, u) - limit, dq = dot(q, u) - limit;
    if (dp <= 0.0) out[m++] = p;
    if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) out[m++] = p + (dp / (dp - dq)) * (q - p);
  }
  return m;
}

}  // namespace

int box_box_contacts(const RigidBody& a, Vec3d half_a, const RigidBody& b, Vec3d half_b,
                     BoxBoxContact (&out)[kMaxBoxBoxContacts]) {
  const OrientedBox boxes[2] = {oriented(a, half_a), oriented(b, half_b)};
  const Vec3d d = a.x - b.x;
  // The reference face: the face axis of least overlap.
  double least = INFINITY;
  int reference = 0, axis = 0;
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < 3; ++i) {
      const Vec3d u = boxes[k].axes[i];
      const double overlap = support(boxes[0], u) + support(boxes[1], u) - std::fabs(dot(d, u));
      if (overlap < least) least = overlap, reference = k, axis = i;
    }
  if (!(least > 0.0)) return 0;  // separated
  const OrientedBox& ref = boxes[reference];
  const OrientedBox& inc = boxes[1 - reference];
  // f: out of the reference box, towards the incident one.
  const Vec3d towards = inc.centre - ref.centre;
  const Vec3d f = dot(towards, ref.axes[axis]) < 0.0 ? -ref.axes[axis] : ref.axes[axis];
  // The incident face: its outward normal most against f.
  int inc_axis = 0;
  for (int i = 1; i < 3; ++i)
    if (std::fabs(dot(f, inc.axes[i])) > std::fabs(dot(f, inc.axes[inc_axis]))) inc_axis = i;
  const Vec3d inc_normal = dot(f, inc.axes[inc_axis]) > 0.0 ? -inc.axes[inc_axis] : inc.axes[inc_axis];
  const Vec3d face_centre = inc.centre + inc.half[inc_axis] * inc_normal;
  const Vec3d s = inc.axes[(inc_axis + 1) % 3], t = inc.axes[(inc_axis + 2) % 3];
  const double hs = inc.half[(inc_axis + 1) % 3], ht = inc.half[(inc_axis + 2) % 3];
  Vec3d polygon[16] = {face_centre + hs * s + ht * t, face_centre - hs * s + ht * t, face_centre - hs * s - ht * t,
                       face_centre + hs * s - ht * t};
  Vec3d scratch[16];
  int n = 4;
  // Clipped to the reference face's four side planes.
  for (int j : {(axis + 1) % 3, (axis + 2) % 3})
    for (double sign : {1.0, -1.0}) {
      const Vec3d u = sign * ref.axes[j];
      n = clip(polygon, n, u, dot(ref.centre, u) + (1.0 + kClipSlack) * ref.half[j], scratch);
      for (int k = 0; k < n; ++k) polygon[k] = scratch[k];
    }
  // The points below the reference face's plane.
  const double plane = dot(ref.centre, f) + ref.half[axis];
  const Vec3d normal = reference == 1 ? f : -f;
  int count = 0;
  for (int k = 0; k < n && count < kMaxBoxBoxContacts; ++k) {
    const double depth = plane - dot(polygon[k], f);
    if (!(depth > 0.0)) continue;
    const Vec3d on_reference = polygon[k] + depth * f;
    BoxBoxContact& c = out[count++];
    c.point_a = reference == 1 ? polygon[k] : on_reference;
    c.point_b = reference == 1 ? on_reference : polygon[k];
    c.normal = normal, c.depth = depth;
  }
  return count;
}

}  // namespace seiche::rigid
