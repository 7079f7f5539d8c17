// A hinge's limit corrected through its anchor (the math is in hinge_limit.hpp): a 4 x 4 solve.
#include "hinge_limit.hpp"

#include <array>
#include <cmath>

namespace seiche::rigid {

namespace {

// What the impulse (p, L) does to the 4 rows (to first order): the anchor's relative move and the
// relative turn about n.
std::array<double, 4> response(const RigidBody& a, const RigidBody& b, Vec3d r_a, Vec3d r_b, Vec3d n, Vec3d p, double l) {
  const Vec3d dx_b = b.inverse_mass * p, dtheta_b = b.world_inverse_inertia(cross(r_b, p) + l * n);
  const Vec3d dx_a = -(a.inverse_mass * p), dtheta_a = -a.world_inverse_inertia(cross(r_a, p) + l * n);
  const Vec3d anchor = (dx_b + cross(dtheta_b, r_b)) - (dx_a + cross(dtheta_a, r_a));
  return {anchor.x, anchor.y, anchor.z, dot(dtheta_b - dtheta_a, n)};
}

// (p, L) with (K + diag(0, 0, 0, alpha_tilde)) (p, L) = rhs; false where K is singular.
bool solve_rows(const RigidBody& a, const RigidBody& b, Vec3d r_a, Vec3d r_b, Vec3d n, double alpha_tilde,
                std::array<double, 4>& x) {
  std::array<double, 16> k{};
  const Vec3d units[3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
  for (int c = 0; c < 4; ++c) {  // column by column: the response to each unit impulse
    const std::array<double, 4> column = c < 3 ? response(a, b, r_a, r_b, n, units[c], 0.0) : response(a, b, r_a, r_b, n, {}, 1.0);
    for (int row = 0; row < 4; ++row) k[std::size_t(row * 4 + c)] = column[std::size_t(row)];
  }
  k[15] += alpha_tilde;
  for (int j = 0; j < 4; ++j) {  // Cholesky, lower triangle in place
    double d = k[std::size_t(j * 4 + j)];
    for (int m = 0; m < j; ++m) d -= k[std::size_t(j * 4 + m)] * k[std::size_t(j * 4 + m)];
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    const double l = std::sqrt(d);
    k[std::size_t(j * 4 + j)] = l;
    for (int i = j + 1; i < 4; ++i) {
      double s = k[std::size_t(i * 4 + j)];
      for (int m = 0; m < j; ++m) s -= k[std::size_t(i * 4 + m)] * k[std::size_t(j * 4 + m)];
      k[std::size_t(i * 4 + j)] = s / l;
    }
  }
  for (int i = 0; i < 4; ++i) {
    for (int m = 0; m < i; ++m) x[std::size_t(i)] -= k[std::size_t(i * 4 + m)] * x[std::size_t(m)];
    x[std::size_t(i)] /= k[std::size_t(i * 4 + i)];
  }
  for (int i = 3; i >= 0; --i) {
    for (int m = i + 1; m < 4; ++m) x[std::size_t(i)] -= k[std::size_t(m * 4 + i)] * x[std::size_t(m)];
    x[std::size_t(i)] /= k[std::size_t(i * 4 + i)];
  }
  return true;
}

}  // namespace

void correct_limit_at_anchor(RigidBody& a, RigidBody& b, Vec3d r_a, Vec3d r_b, Vec3d axis, double over,
                             double alpha_tilde, double& lambda) {
  const Vec3d gap = (b.x + r_b) - (a.x + r_a);
  std::array<double, 4> x{-gap.x, -gap.y, -gap.z, -over - alpha_tilde * lambda};
  if (!solve_rows(a, b, r_a, r_b, axis, alpha_tilde, x)) return;
  const Vec3d p{x[0], x[1], x[2]};
  lambda += x[3];
  if (!b.fixed()) {
    b.x += b.inverse_mass * p;
    b.q = rotate_by_small(b.q, b.world_inverse_inertia(cross(r_b, p) + x[3] * axis));
  }
  if (!a.fixed()) {
    a.x -= a.inverse_mass * p;
    a.q = rotate_by_small(a.q, -a.world_inverse_inertia(cross(r_a, p) + x[3] * axis));
  }
}

}  // namespace seiche::rigid
