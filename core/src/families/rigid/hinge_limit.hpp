// A hinge's limit corrected through its anchor (the correction after the tree solve, joint.hpp):
// the turn of body b against body a about the hinge's axis n back to the limit, and the
// connector points' gap closed, in one XPBD step of 4 rows.
//
// Rows over the two bodies: the connector points' relative move (3) and the relative turn about
// n (1). Impulses: p at the anchor (+p on b, -p on a) and the couple L n (+ on b, - on a), which
// move the bodies by
//   dx_b = p / m_b,  dtheta_b = I_b^-1 (r_b x p + L n),
//   dx_a = -p / m_a, dtheta_a = -I_a^-1 (r_a x p + L n).
// (p, L) solves (K + diag(0, 0, 0, alpha~)) (p, L) = (-(P_b - P_a), -C - alpha~ lambda), K = J M^-1
// J^T of those 4 rows (symmetric positive definite where a body can move; a fixed body and the
// world take none of it), C = phi - clamp(phi, lower, upper), alpha~ = compliance / h^2, and
// lambda += L.
// Why the anchor with the limit: a turn about the body's centre alone (the plain angular
// correction, body_correction.hpp) moves the anchor, which the tree puts back in the next
// iteration and the limit takes away again; the substep ended with the anchor apart, and the
// velocities derived from the positions sent the door of scenes/hinge_door.json back from its
// limit at 0.38-0.53 rad/s after hitting it at 1.98 rad/s. Turned about the anchor it stops there
// (an inelastic stop: the position solve leaves no approach velocity).
#pragma once

#include "rigid_body.hpp"

namespace seiche::rigid {

/// Turns b against a about unit `axis` by -over (the limit's error C, rad) through the hinge's
/// anchor and closes the anchor's gap P_b - P_a; levers r_a, r_b in the world frame;
/// alpha_tilde = compliance / h^2; lambda the limit's multiplier. Nothing changes where the
/// system is singular (both bodies fixed) or not finite.
void correct_limit_at_anchor(RigidBody& a, RigidBody& b, Vec3d r_a, Vec3d r_b, Vec3d axis, double over,
                             double alpha_tilde, double& lambda);

}  // namespace seiche::rigid
