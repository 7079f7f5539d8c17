// XPBD corrections of rigid bodies through their generalized inverse masses (the formulas are
// in body_correction.hpp).
#include "body_correction.hpp"

namespace seiche::rigid {

double positional_inverse_mass(const RigidBody& b, Vec3d r, Vec3d n) {
  if (b.fixed()) return 0.0;
  const Vec3d rn = cross(r, n);
  return b.inverse_mass + dot(rn, b.world_inverse_inertia(rn));
}

double angular_inverse_mass(const RigidBody& b, Vec3d n) {
  if (b.fixed()) return 0.0;
  return dot(n, b.world_inverse_inertia(n));
}

double patch_inverse_mass(const RigidBody& b, Vec3d r, Vec3d t, Vec3d n) {
  const double twist = dot(cross(r, t), n);
  return b.inverse_mass + twist * twist * angular_inverse_mass(b, n);
}

void apply_positional_impulse(RigidBody& b, Vec3d r, Vec3d p) {
  if (b.fixed()) return;
  b.x += b.inverse_mass * p;
  b.q = rotate_by_small(b.q, b.world_inverse_inertia(cross(r, p)));
}

void apply_angular_impulse(RigidBody& b, Vec3d p) {
  if (b.fixed()) return;
  b.q = rotate_by_small(b.q, b.world_inverse_inertia(p));
}

double correct_position(RigidBody& a, RigidBody& b, Vec3d r_a, Vec3d r_b, Vec3d error, double alpha_tilde,
                        double& lambda) {
  const double c = length(error);
  if (!(c > 0.0)) return 0.0;
  const Vec3d n = (1.0 / c) * error;
  const double denominator = positional_inverse_mass(a, r_a, n) + positional_inverse_mass(b, r_b, n) + alpha_tilde;
  if (!(denominator > 0.0)) return 0.0;
  const double dlambda = (-c - alpha_tilde * lambda) / denominator;
  lambda += dlambda;
  const Vec3d p = dlambda * n;
  apply_positional_impulse(b, r_b, p);
  apply_positional_impulse(a, r_a, -p);
  return dlambda;
}

double correct_rotation(RigidBody& a, RigidBody& b, Vec3d error, double alpha_tilde, double& lambda) {
  const double c = length(error);
  if (!(c > 0.0)) return 0.0;
  const Vec3d n = (1.0 / c) * error;
  const double denominator = angular_inverse_mass(a, n) + angular_inverse_mass(b, n) + alpha_tilde;
  if (!(denominator > 0.0)) return 0.0;
  const double dlambda = (-c - alpha_tilde * lambda) / denominator;
  lambda += dlambda;
  const Vec3d p = dlambda * n;
  apply_angular_impulse(b, p);
  apply_angular_impulse(a, -p);
  return dlambda;
}

}  // namespace seiche::rigid
