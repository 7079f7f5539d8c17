// The contacts of a capsule's side (its segment between the cap centres) with another capsule or
// a box (between bodies, and against a box collider seen as a body: world_contacts.hpp), and with
// a sphere or capsule collider (world_contacts.hpp), which the
// capsule's contact balls at its cap centres miss: two capsules crossed side on side, or a capsule
// lying across a box's edge or over a face narrower than the capsule, have no cap centre near the
// other body. Where a segment end is the closest
// point, its cap ball is the contact already (a ball against a solid is exact): these add only
// points inside the segment.
//   Capsule against capsule: the closest points c_a = P_a + s d_a, c_b = P_b + t d_b of the two
//     segments (r = P_a - P_b; s = ((d_a.d_b)(d_b.r) - (d_b.d_b)(d_a.r)) / D, t = ((d_a.d_a)(d_b.r)
//     - (d_a.d_b)(d_a.r)) / D, D = |d_a|^2 |d_b|^2 - (d_a.d_b)^2), where both lie strictly inside
//     (0 < s, t < 1; else the closest point is an end: the balls) and the segments are not
//     parallel (D > 1e-12 |d_a|^2 |d_b|^2: parallel ones touch at an end's ball). Depth
//     rho_a + rho_b - |c_a - c_b|, normal n = (c_a - c_b) / |c_a - c_b| (where the axes meet:
//     their cross product turned towards x_a - x_b), a's point c_a - rho_a n, b's c_b + rho_b n.
//   Capsule against box (in the box's frame, half sizes h; nothing where both ends lie beyond one
//     face of the box grown by the radius, |p_k| > h_k + rho on one side): f(t) = sdf_box(A + t (B - A)) is
//     convex (the signed distance of a convex solid), so its least t* is found by ternary search
//     (64 steps, each keeping 2/3 of the bracket: 5e-12 of the segment). Its face: the axis k where p(t*) sticks out most,
//     |p_k| - h_k. Like a box on a face, the segment clipped to that face's sides (|p_j| <= h_j,
//     j != k) gives its two ends t_0 <= t_1, and the segment's points there rest on the face (a
//     capsule across a narrower box: one at each edge); t* adds the deepest point where it is
//     strictly below both segment ends (a capsule across an edge). Each of those inside (0, 1)
//     is a ball of the capsule's radius against the box (world_surfaces.hpp's penetration()).
//   Capsule against a sphere or capsule collider (world_contacts.hpp: a collider has no cap balls
//     of its own): against a sphere of centre c, the segment's point closest to c, t* =
//     clamp((c - P).d / d.d, 0, 1), where it lies strictly inside (0 < t* < 1; else the closest
//     point is an end: its cap ball); against a capsule, the two segments' closest points as two
//     capsules crossed (t*), and where they do not cross inside both, the closest point lies at an
//     end of one of them: of the body's, its cap ball; of the collider's, the body segment's point
//     closest to that end (t_0 for the collider's first end, t_1 for its second; a capsule lying
//     along a shorter one rests on both). Each of these a ball of the capsule's radius against the
//     collider's solid (world_surfaces.hpp's penetration(): exact for a ball).
// Every contact in a fixed role (t_0, t_1, t*; the crossing of two capsules is t*'s), so that a
// pair's slot for it (body_contacts.hpp) keeps its meaning from one pass to the next.
#pragma once

#include "box_box.hpp"
#include "rigid_body.hpp"
#include "world_surfaces.hpp"

namespace seiche::rigid {

inline constexpr int kCapsuleSideRoles = 3;  ///< t_0, t_1, t* (above)

/// Whether solids a and b (body frames) have side contacts: a capsule with a capsule or a box.
bool has_capsule_sides(const SolidSurface& a, const SolidSurface& b);

/// The side contacts of bodies a and b (solids in their body frames, has_capsule_sides()), one
/// per role; a role without contact has depth 0. Returns how many have depth > 0.
int capsule_side_contacts(const RigidBody& a, const SolidSurface& solid_a, const RigidBody& b,
                          const SolidSurface& solid_b, BoxBoxContact (&out)[kCapsuleSideRoles]);

/// The side contacts of capsule body `capsule` (its solid in its body frame) with a sphere or
/// capsule collider seen as a body (`round`: its solid about `frame`), one per role (above); a
/// role without contact has depth 0. Returns how many have depth > 0.
int capsule_round_collider_contacts(const RigidBody& capsule, const SolidSurface& capsule_solid, const RigidBody& frame,
                                    const SolidSurface& round, BoxBoxContact (&out)[kCapsuleSideRoles]);

}  // namespace seiche::rigid
