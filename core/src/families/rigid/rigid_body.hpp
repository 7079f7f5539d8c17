// A rigid body's state and its integration per substep (Müller et al. 2020, "Detailed Rigid
// Body Simulation with Extended Position Based Dynamics", Algorithm 2), in double precision:
// a scene has few bodies, so the cost is nothing, and joints act through lever arms of metres
// on corrections of micrometres, where float32's 7 digits would show as drift and as energy
// noise. The particle store stays float32; a body is not in it.
//
// State: centre of mass x, orientation q (unit quaternion, body to world), velocity v, angular
// velocity omega (world frame); constants: inverse mass 1/m and the principal moments I of the
// inertia tensor in the body frame (body_shape.hpp). A fixed body has 1/m = 0 and I^-1 = 0.
//
// Per substep of length h:
//   predict  x_prev = x, q_prev = q
//            v += h g,  x += h v
//            omega += h I^-1 (tau - omega x (I omega))    (the gyroscopic term; tau = 0: gravity
//                                                          acts at the centre of mass)
//            q = exp(h omega) q, normalized
//   (the joints correct x and q)
//   update   v = (x - x_prev) / h,  omega = log(q q_prev^-1) / h
// The rotational part is taken in a form that keeps what the torque-free motion keeps, to
// rounding: the world angular momentum and the rotational energy. In the body frame, with
// L = I omega,
//   L' = exp(-phi) L,  phi = h I^-1 (L + L') / 2     (implicit midpoint; fixed-point passes)
//   q' = exp(R(q) phi) q,  omega' = R(q') I^-1 L'
// L' is L turned about phi, so |L'| = |L|, and L' - L is perpendicular to phi, so the energy
// E = L . I^-1 L / 2 changes by (L' - L) . (phi / h) = 0; and the body turns by the same phi,
// so R(q') L' = R(q) L: the world angular momentum stays. To first order it is the paper's
// omega += -h I^-1 (omega x I omega) followed by q += h/2 [omega, 0] q, whose explicit
// gyroscopic step grows |L| by 1 + O(h^2 |omega|^2) and whose linearized quaternion step and
// read-back (omega = 2 vec(dq) / h) lose a fraction h^2 |omega|^2 / 4 of the rotational energy
// per substep (0.9 % over 2 s at 3 rad/s and 8 substeps of a 60 Hz frame).
// The body turns by phi, the midpoint's rotation, but ends the substep with omega', so the
// update reads omega back from the turn (the exact logarithm, on the w >= 0 half: the paper's
// sign fix) and adds the difference the predict step left, omega' - phi / h (body frame, turned
// with the body): without corrections the update returns omega' exactly, and a joint's
// correction of q changes omega as in the paper. A substep resolves turns of less than half a
// revolution (|omega| h < pi: 1500 rad/s at 8 substeps of a 60 Hz frame); the logarithm reads a
// larger one as the shorter turn the other way.
#pragma once

#include "rigid_math.hpp"

namespace seiche::rigid {

struct RigidBody {
  Vec3d x;      ///< centre of mass (m)
  Quatd q;      ///< body to world
  Vec3d v;      ///< m/s
  Vec3d omega;  ///< rad/s, world frame
  Vec3d x_prev; ///< at the start of the substep
  Quatd q_prev;
  Vec3d gyroscopic_remainder;  ///< omega' - phi / h of this substep's predict (body frame)
  double inverse_mass = 0.0;  ///< 1/kg; 0: fixed
  Vec3d inertia;              ///< principal moments in the body frame (kg m^2)
  Vec3d inverse_inertia;      ///< their inverses; 0: fixed

  bool fixed() const { return inverse_mass == 0.0; }
  /// I^-1 v in the world frame: R I^-1 R^T v.
  Vec3d world_inverse_inertia(Vec3d v) const { return rotate(q, scale(inverse_inertia, rotate_back(q, v))); }
  /// I v in the world frame: R I R^T v.
  Vec3d world_inertia(Vec3d v) const { return rotate(q, scale(inertia, rotate_back(q, v))); }
  /// A body point given in the body frame, in the world frame now.
  Vec3d world_point(Vec3d local) const { return x + rotate(q, local); }
};

/// A movable body with mass m and principal moments `inertia`; a fixed one where fixed.
RigidBody make_body(Vec3d x, Quatd q, Vec3d v, Vec3d omega, double mass, Vec3d inertia, bool fixed);

/// The predict step above (nothing for a fixed body).
void predict_body(RigidBody& b, Vec3d gravity, double h);
/// The update step above (nothing for a fixed body).
void update_body_velocity(RigidBody& b, double h);

/// Kinetic energy m |v|^2 / 2 + omega . I omega / 2 (J); 0 for a fixed body.
double kinetic_energy(const RigidBody& b);
/// Angular momentum about the centre of mass, world frame: I omega (kg m^2/s).
Vec3d angular_momentum(const RigidBody& b);

}  // namespace seiche::rigid
