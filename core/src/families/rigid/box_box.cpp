// The contact of two boxes by separating axes and clipping (the math is in box_box.hpp).
#include "box_box.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>

namespace seiche::rigid {

namespace {

// The reference face's side planes are moved out by this share of its half size: an incident edge
// that lies on a side (equal boxes stacked) stays in when rounding puts it a few ulps out.
constexpr double kClipSlack = 1e-9;

// The contacts' features (box_box.hpp): per reference face, kFeaturesPerFace numbers, the incident
// corners first, then the incident edges' crossings of the side planes, then the reference corners.
constexpr int kEdgeCrossings = 8, kReferenceCorners = kEdgeCrossings + 12 * 4;

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

// A vertex of the clipped incident face: its point, its feature (box_box.hpp: an incident corner,
// an incident edge across a side plane, or a reference corner) and the line its edge to the next
// vertex lies on (an incident edge e, 0..11, or the side plane kOnSide + k).
struct FaceVertex {
  Vec3d p;
  int feature = 0;
  int edge = 0;
};
constexpr int kOnSide = 16;

// The feature where an edge on line `edge` crosses side plane `side` (0..3: 2 j + (sign < 0), j
// the face's first or second other axis): an incident edge's crossing, or a reference corner.
int crossing_feature(int edge, int side) {
  if (edge < kOnSide) return kEdgeCrossings + 4 * edge + side;
  const int other = edge - kOnSide;
  if (other / 2 == side / 2) return kReferenceCorners + 4;  // parallel sides: not met by a real polygon
  const int first = other / 2 == 0 ? other : side, second = other / 2 == 0 ? side : other;
  return kReferenceCorners + 2 * (first % 2) + (second % 2);
}

// The part of the polygon in[0..n) where p.u <= limit (Sutherland-Hodgman, one plane: side plane
// `side`), each vertex with its feature and the line of its next edge.
int clip(const FaceVertex* in, int n, Vec3d u, double limit, int side, FaceVertex* out) {
  int m = 0;
  for (int k = 0; k < n; ++k) {
    const FaceVertex &p = in[k], &q = in[(k + 1) % n];
    const double dp = dot(p.p, u) - limit, dq = dot(q.p, u) - limit;
    if (dp <= 0.0) out[m++] = {p.p, p.feature, dp == 0.0 && dq > 0.0 ? kOnSide + side : p.edge};
    if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0))
      out[m++] = {p.p + (dp / (dp - dq)) * (q.p - p.p), crossing_feature(p.edge, side), dp < 0.0 ? kOnSide + side : p.edge};
  }
  return m;
}

// The corner of a box at body-frame signs (x, y, z), numbered as its contact points
// (world_contacts.cpp): 4 (x > 0) + 2 (y > 0) + (z > 0).
int corner_index(const double (&sign)[3]) { return (sign[0] > 0.0 ? 4 : 0) + (sign[1] > 0.0 ? 2 : 0) + (sign[2] > 0.0 ? 1 : 0); }
// The edge of a box along axis k between corners at `sign` (the other two axes' signs): 4 k + 2
// (first other > 0) + (second other > 0).
int edge_index(int k, const double (&sign)[3]) {
  const int first = k == 0 ? 1 : 0, second = k == 2 ? 1 : 2;
  return 4 * k + (sign[first] > 0.0 ? 2 : 0) + (sign[second] > 0.0 ? 1 : 0);
}

// The edge-edge axes u = A_i x B_j whose edges are not parallel: |A_i x B_j| = sin of their angle
// above kParallelSine (nearly parallel edges have no reliable cross product; their faces and
// corners hold them).
constexpr double kParallelSine = 1e-6;
// An edge axis is taken only where its overlap is below this share of the least face overlap: a
// face holds a resting box with 4 points, an edge with 1, so near-ties (a box turned about the
// normal on another, where A_x x B_z is the face normal) stay with the face.
constexpr double kEdgePreference = 0.95;
// An edge axis within rounding of a face axis (|cos| > 1 - kSameAxis) is that face axis.
constexpr double kSameAxis = 1e-12;

struct EdgeAxis {
  int index = -1;        // 3 i + j: a's edge along A_i, b's along B_j; -1: none
  Vec3d u;               // unit, from a towards b
  double overlap = INFINITY;
};

// Whether unit u is one of the six face axes, to rounding (A_i x B_j is one where B_j is
// perpendicular to A_i and A_i's two other axes, as with a box turned about a face normal): that
// face's test decides it.
bool along_face_axis(const OrientedBox (&boxes)[2], Vec3d u) {
  for (const OrientedBox& box : boxes)
    for (const Vec3d& axis : box.axes)
      if (std::fabs(dot(u, axis)) > 1.0 - kSameAxis) return true;
  return false;
}

// The edge-edge axis of least overlap o(u) = support_a(u) + support_b(u) - |(x_a - x_b).u| (ties:
// the lower 3 i + j), d = x_a - x_b; false where one separates the boxes (o <= 0).
bool least_edge_axis(const OrientedBox (&boxes)[2], Vec3d d, EdgeAxis& out) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vec3d c = cross(boxes[0].axes[i], boxes[1].axes[j]);
      const double sine = length(c);
      if (!(sine > kParallelSine)) continue;
      Vec3d u = (1.0 / sine) * c;
      if (along_face_axis(boxes, u)) continue;
      const double along = -dot(d, u);  // (x_b - x_a).u
      const double overlap = support(boxes[0], u) + support(boxes[1], u) - std::fabs(along);
      if (!(overlap > 0.0)) return false;
      if (overlap < out.overlap) {
        if (along < 0.0) u = -u;
        out.index = 3 * i + j, out.u = u, out.overlap = overlap;
      }
    }
  return true;
}

// The supporting edge of `box` along axis i farthest along `u`: its centre and half length.
Vec3d edge_centre(const OrientedBox& box, int i, Vec3d u) {
  Vec3d c = box.centre;
  for (int k = 0; k < 3; ++k)
    if (k != i) c += (dot(u, box.axes[k]) < 0.0 ? -box.half[k] : box.half[k]) * box.axes[k];
  return c;
}

// Two boxes crossed edge on edge: a's edge farthest along u (towards b) and b's farthest along -u,
// their closest points P_a, P_b (each clamped to its edge); one contact: a's point P_a, b's P_b,
// depth the axis's overlap (= (P_a - P_b).u where neither is clamped), normal -u (a pushed away
// from b).
BoxBoxContact edge_edge_contact(const OrientedBox (&boxes)[2], const EdgeAxis& edge) {
  const int i = edge.index / 3, j = edge.index % 3;
  const Vec3d p = edge_centre(boxes[0], i, edge.u), q = edge_centre(boxes[1], j, -edge.u);
  const Vec3d e = boxes[0].axes[i], f = boxes[1].axes[j];
  // The closest points p + s e, q + t f of the two lines (unit directions, not parallel), with
  // r = q - p: s = (e.r - (e.f)(f.r)) / (1 - (e.f)^2), t = (e.f) s - f.r; t clamped to b's edge,
  // then s again for that t (s = e.r + (e.f) t) clamped to a's.
  const Vec3d r = q - p;
  const double ef = dot(e, f), denominator = 1.0 - ef * ef;
  const double s_free = denominator > 0.0 ? (dot(e, r) - ef * dot(f, r)) / denominator : 0.0;
  const double t = std::clamp(ef * s_free - dot(f, r), -boxes[1].half[j], boxes[1].half[j]);
  const double s = std::clamp(dot(e, r) + ef * t, -boxes[0].half[i], boxes[0].half[i]);
  BoxBoxContact c;
  c.point_a = p + s * e, c.point_b = q + t * f;
  c.normal = -edge.u, c.depth = edge.overlap;
  // The two edges: their axes and the signs of their other two axes (edge_centre's).
  int signs = 0;
  for (int k = 0; k < 3; ++k) {
    if (k != i) signs = 2 * signs + (dot(edge.u, boxes[0].axes[k]) < 0.0 ? 0 : 1);
    if (k != j) signs = 2 * signs + (dot(-edge.u, boxes[1].axes[k]) < 0.0 ? 0 : 1);
  }
  c.feature = kEdgeEdgeFeatures + 16 * edge.index + signs;
  return c;
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
  // The edge-edge axes: separated along one, or crossed edge on edge where one overlaps least.
  EdgeAxis edge;
  if (!least_edge_axis(boxes, d, edge)) return 0;
  if (edge.index >= 0 && edge.overlap < kEdgePreference * least) {
    out[0] = edge_edge_contact(boxes, edge);
    return 1;
  }
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
  // Its corners in the order (+s +t), (-s +t), (-s -t), (+s -t), each with its corner's and its
  // next edge's numbers in the incident box.
  const int is = (inc_axis + 1) % 3, it = (inc_axis + 2) % 3;
  const double normal_sign = dot(inc_normal, inc.axes[inc_axis]) > 0.0 ? 1.0 : -1.0;
  const double corner_s[4] = {1.0, -1.0, -1.0, 1.0}, corner_t[4] = {1.0, 1.0, -1.0, -1.0};
  FaceVertex polygon[16];
  for (int k = 0; k < 4; ++k) {
    double sign[3];
    sign[inc_axis] = normal_sign, sign[is] = corner_s[k], sign[it] = corner_t[k];
    polygon[k].p = face_centre + (corner_s[k] * hs) * s + (corner_t[k] * ht) * t;
    polygon[k].feature = corner_index(sign);
    // The edge to the next corner runs along s (k even) or t (k odd), at the other's sign.
    polygon[k].edge = edge_index(k % 2 == 0 ? is : it, sign);
  }
  FaceVertex scratch[16];
  int n = 4;
  // Clipped to the reference face's four side planes.
  for (int j : {0, 1})
    for (double sign : {1.0, -1.0}) {
      const int side_axis = (axis + 1 + j) % 3;
      const Vec3d u = sign * ref.axes[side_axis];
      n = clip(polygon, n, u, dot(ref.centre, u) + (1.0 + kClipSlack) * ref.half[side_axis], 2 * j + (sign < 0.0 ? 1 : 0),
               scratch);
      for (int k = 0; k < n; ++k) polygon[k] = scratch[k];
    }
  // The points below the reference face's plane.
  const double plane = dot(ref.centre, f) + ref.half[axis];
  const Vec3d normal = reference == 1 ? f : -f;
  int count = 0;
  const int face = 2 * axis + (dot(f, ref.axes[axis]) > 0.0 ? 0 : 1);
  for (int k = 0; k < n && count < kMaxBoxBoxContacts; ++k) {
    const double depth = plane - dot(polygon[k].p, f);
    if (!(depth > 0.0)) continue;
    const Vec3d on_reference = polygon[k].p + depth * f;
    BoxBoxContact& c = out[count++];
    c.point_a = reference == 1 ? polygon[k].p : on_reference;
    c.point_b = reference == 1 ? on_reference : polygon[k].p;
    c.normal = normal, c.depth = depth;
    c.feature = (6 * reference + face) * kFeaturesPerFace + polygon[k].feature;
  }
  return count;
}

}  // namespace seiche::rigid
