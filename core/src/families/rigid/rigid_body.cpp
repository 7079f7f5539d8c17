// A rigid body's integration per substep (the scheme and its reasons are in rigid_body.hpp).
#include "rigid_body.hpp"

namespace seiche::rigid {

namespace {
// At most this many fixed-point passes of the implicit gyroscopic rotation. Each shrinks the
// error by about h |omega| times the anisotropy of I, so at the speeds a substep resolves
// (h |omega| < 0.1) the passes reach their fixed point to the last bit in a handful; the loop
// stops there (the same bits on every machine: the passes are the same arithmetic).
constexpr int kGyroscopicPasses = 16;
}  // namespace

RigidBody make_body(Vec3d x, Quatd q, Vec3d v, Vec3d omega, double mass, Vec3d inertia, bool fixed) {
  RigidBody b;
  b.x = b.x_prev = x;
  b.q = b.q_prev = normalized(q);
  b.inertia = inertia;
  if (!fixed) {
    b.v = v, b.omega = omega;
    b.inverse_mass = mass > 0.0 ? 1.0 / mass : 0.0;
    const auto inv = [](double i) { return i > 0.0 ? 1.0 / i : 0.0; };
    b.inverse_inertia = {inv(inertia.x), inv(inertia.y), inv(inertia.z)};
  }
  return b;
}

void predict_body(RigidBody& b, Vec3d gravity, double h) {
  b.x_prev = b.x;
  b.q_prev = b.q;
  if (b.fixed()) return;
  b.v += h * gravity;
  b.x += h * b.v;
  // The gyroscopic term as a rotation of L about the implicit midpoint's omega (rigid_body.hpp).
  const Vec3d momentum = scale(b.inertia, rotate_back(b.q, b.omega));
  Vec3d next = momentum, turn{};
  for (int pass = 0; pass < kGyroscopicPasses; ++pass) {
    turn = h * scale(b.inverse_inertia, 0.5 * (momentum + next));
    const Vec3d again = rotate(rotation_quaternion(-turn), momentum);
    const bool converged = again.x == next.x && again.y == next.y && again.z == next.z;
    next = again;
    if (converged) break;
  }
  const Vec3d omega_next = scale(b.inverse_inertia, next);
  b.gyroscopic_remainder = omega_next - (1.0 / h) * turn;
  b.q = normalized(rotation_quaternion(rotate(b.q, turn)) * b.q);
  b.omega = rotate(b.q, omega_next);
}

void update_body_velocity(RigidBody& b, double h) {
  if (b.fixed()) return;
  const double inverse_h = 1.0 / h;
  b.v = inverse_h * (b.x - b.x_prev);
  b.omega = inverse_h * rotation_vector(b.q * conjugate(b.q_prev)) + rotate(b.q, b.gyroscopic_remainder);
}

double kinetic_energy(const RigidBody& b) {
  if (b.fixed()) return 0.0;
  const Vec3d omega_body = rotate_back(b.q, b.omega);
  return 0.5 * dot(b.v, b.v) / b.inverse_mass + 0.5 * dot(omega_body, scale(b.inertia, omega_body));
}

Vec3d angular_momentum(const RigidBody& b) { return b.world_inertia(b.omega); }

}  // namespace seiche::rigid
