// The contact of two boxes (face against face, edge or corner; edge against edge), by separating axes
// and clipping, as in Box2D and ODE (Gottschalk's separating axes; Sutherland-Hodgman clipping):
// box corners alone miss two boxes face on face when neither has a corner inside the other (a box
// turned about the normal on an equal box: every corner sticks out).
//   Reference face: of the 6 face axes u of both boxes (A_i, B_i, half sizes h_a, h_b), the one of
//     least overlap o(u) = sum_i h_a,i |u.A_i| + sum_i h_b,i |u.B_i| - |(x_a - x_b).u| (ties: a's
//     axes first, x before y before z); its box is the reference box R, its face towards the other
//     box (outward normal f) the reference face, the other box the incident box I.
//   Incident face: I's face whose outward normal is most against f; its 4 corners, clipped to the
//     reference face's side planes |(p - x_R).R_j| <= h_R,j (1 + 1e-9) (j the face's two other axes;
//     the slack keeps an edge that lies on a side, as equal stacked boxes have): up to 8 points p.
//   Contacts: each p below the reference face's plane, depth d = (x_R + h_R,i f - p).f > 0; I's
//     point p, R's point p + d f, and the normal n = f turned to point at a (f where R is b).
//   Features: each contact names what touches there, so that the pair's slot for it
//     (body_contacts.hpp) stays with it while other points come and go: per reference face (of
//     12: 6 of a, then 6 of b; 64 numbers each) the incident box's corner (0-7, numbered as its
//     contact points), or one of its 12 edges across one of the 4 side planes (8 + 4 e + k), or a
//     corner of the reference face where the clipped polygon runs along two side planes (56 +
//     k); a vertex of the clipped polygon carries its feature through the clipping, and each of
//     its edges the line it lies on (an incident edge or a side plane).
//   Edge against edge (two boxes crossed): the 9 axes u = A_i x B_j of edges that are not
//     parallel (|A_i x B_j| > 1e-6) nor along a face axis (to 1e-12: that face's test), with the
//     same overlap o(u). One of them <= 0 separates the boxes (no contact). Where the least, ties
//     to the lower 3 i + j, is below 0.95 times the least face overlap (a face holds a box with 4
//     points, an edge with 1: near-ties stay with the face), u turned from a towards b: a's edge
//     along A_i farthest along u, b's along B_j farthest along -u, their closest points P_a, P_b
//     (each on its edge), one contact with depth o(u) and normal -u; its feature 768 + 16 (3 i + j)
//     + the two edges' sides (the signs of their other axes along u).
#pragma once

#include "rigid_body.hpp"

namespace seiche::rigid {

struct BoxBoxContact {
  Vec3d point_a, point_b;  ///< world frame
  Vec3d normal;            ///< unit, the way a is pushed
  double depth = 0.0;      ///< > 0 (m)
  int feature = 0;         ///< which features touch, 0 to kBoxBoxFeatures - 1 (above)
};

inline constexpr int kMaxBoxBoxContacts = 8;
inline constexpr int kFeaturesPerFace = 64;  ///< 8 corners, 12 edges x 4 sides, 4 reference corners (+1 spare)
inline constexpr int kEdgeEdgeFeatures = 12 * kFeaturesPerFace;  ///< after the 12 reference faces'
inline constexpr int kBoxBoxFeatures = kEdgeEdgeFeatures + 9 * 16;

/// The contacts of box a (half sizes half_a, body frame) and box b; returns how many (0 to 8).
int box_box_contacts(const RigidBody& a, Vec3d half_a, const RigidBody& b, Vec3d half_b,
                     BoxBoxContact (&out)[kMaxBoxBoxContacts]);

}  // namespace seiche::rigid
