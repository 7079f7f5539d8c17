// Corrections of rigid bodies through their generalized inverse masses, XPBD (Müller et al.
// 2020, sections 3.3.1-3.3.2): the one place where a constraint moves a body. The joints call
// it; a later coupling of bodies to particles calls it too (a correction of a body's surface
// particle becomes a positional correction at that particle's lever arm r).
//
// Positional: two body points P_a = x_a + r_a and P_b = x_b + r_b (r in the world frame) with
// an error d = P_b - P_a (what is to become zero): C = |d|, n = d / |d|,
//   w_i = 1/m_i + (r_i x n)^T I_i^-1 (r_i x n)        (I^-1 in the world frame)
//   dlambda = (-C - alpha~ lambda) / (w_a + w_b + alpha~),  alpha~ = alpha / h^2,  lambda += dlambda
//   p = dlambda n:  x_b += p / m_b,  q_b += 1/2 [I_b^-1 (r_b x p), 0] q_b   (then normalized)
//                   x_a -= p / m_a,  q_a -= 1/2 [I_a^-1 (r_a x p), 0] q_a
// Angular: body b is turned by the rotation vector e relative to where the constraint wants it
// (relative to body a): C = |e|, n = e / |e|, w_i = n^T I_i^-1 n, the same dlambda, p = dlambda n:
//   q_b += 1/2 [I_b^-1 p, 0] q_b,  q_a -= 1/2 [I_a^-1 p, 0] q_a.
// A fixed body (1/m = 0, I^-1 = 0) has w = 0 and does not move: the world is one. An error of
// zero length or a zero denominator changes nothing (no division by zero).
#pragma once

#include "rigid_body.hpp"

namespace seiche::rigid {

/// w = 1/m + (r x n)^T I^-1 (r x n) of body point r (world frame, from the centre) along unit n.
double positional_inverse_mass(const RigidBody& b, Vec3d r, Vec3d n);
/// w = n^T I^-1 n about unit axis n.
double angular_inverse_mass(const RigidBody& b, Vec3d n);
/// A face patch's inverse mass at lever r along unit t, on a surface of unit normal n: its
/// translation and its turn about n only (the normals hold the tipping):
/// 1/m + ((r x t).n)^2 n^T I^-1 n.
double patch_inverse_mass(const RigidBody& b, Vec3d r, Vec3d t, Vec3d n);

/// Moves body point r (world frame) by the impulse p: x += p / m, q turned by I^-1 (r x p).
void apply_positional_impulse(RigidBody& b, Vec3d r, Vec3d p);
/// Turns the body by I^-1 p.
void apply_angular_impulse(RigidBody& b, Vec3d p);

/// One XPBD step of the positional constraint above; alpha_tilde = compliance / h^2. Returns the
/// multiplier's step dlambda.
double correct_position(RigidBody& a, RigidBody& b, Vec3d r_a, Vec3d r_b, Vec3d error, double alpha_tilde,
                        double& lambda);
/// One XPBD step of the angular constraint above.
double correct_rotation(RigidBody& a, RigidBody& b, Vec3d error, double alpha_tilde, double& lambda);

}  // namespace seiche::rigid
