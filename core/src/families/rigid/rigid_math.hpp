// Double-precision 3-vectors and unit quaternions for the rigid bodies (rigid_body.hpp): the few
// operations the integration and the joints need, written out (+ - * / sqrt, and the sin, cos and
// atan2 of portable_trig.hpp for the exponential and logarithm maps), serial and in a fixed order,
// so that the bits depend on neither the thread count, nor the machine, nor the order of anything
// but the scene.
//
// A quaternion q = [w, x, y, z] (w the scalar part) rotates a vector v by R(q) v = q [0, v] q*.
// Rotation vectors: exp(phi) = [cos(|phi|/2), sin(|phi|/2) phi/|phi|] and its inverse log(q),
// the rotation vector of angle 2 atan2(|vec q|, w) about vec q, taken on the half of the
// double cover with w >= 0 (the shorter rotation; the "sign fix" of Müller et al. 2020).
#pragma once

#include <cmath>

#include "portable_trig.hpp"

namespace seiche::rigid {

struct Vec3d {
  double x = 0.0, y = 0.0, z = 0.0;
};

inline Vec3d operator+(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3d operator-(Vec3d a) { return {-a.x, -a.y, -a.z}; }
inline Vec3d operator*(double s, Vec3d a) { return {s * a.x, s * a.y, s * a.z}; }
inline Vec3d& operator+=(Vec3d& a, Vec3d b) { return a = a + b; }
inline Vec3d& operator-=(Vec3d& a, Vec3d b) { return a = a - b; }
inline double dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(Vec3d a) { return std::sqrt(dot(a, a)); }
/// Component-wise product: a diagonal matrix (the body-frame inertia) times a vector.
inline Vec3d scale(Vec3d diagonal, Vec3d a) { return {diagonal.x * a.x, diagonal.y * a.y, diagonal.z * a.z}; }
/// a / |a|, or zero when |a| is zero (or not finite).
inline Vec3d normalized_or_zero(Vec3d a) {
  const double l = length(a);
  return l > 0.0 && std::isfinite(l) ? (1.0 / l) * a : Vec3d{};
}

struct Quatd {
  double w = 1.0, x = 0.0, y = 0.0, z = 0.0;
  Vec3d vec() const { return {x, y, z}; }
};

inline Quatd operator*(Quatd a, Quatd b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
inline Quatd conjugate(Quatd q) { return {q.w, -q.x, -q.y, -q.z}; }
/// q / |q|; the identity for a zero (or non-finite) quaternion.
inline Quatd normalized(Quatd q) {
  const double l = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(l > 0.0) || !std::isfinite(l)) return {};
  const double s = 1.0 / l;
  return {s * q.w, s * q.x, s * q.y, s * q.z};
}

/// R(q) v for a unit q: v + 2 w (u x v) + 2 u x (u x v), u = vec q.
inline Vec3d rotate(Quatd q, Vec3d v) {
  const Vec3d u = q.vec();
  const Vec3d t = 2.0 * cross(u, v);
  return v + q.w * t + cross(u, t);
}
/// R(q)^T v for a unit q.
inline Vec3d rotate_back(Quatd q, Vec3d v) { return rotate(conjugate(q), v); }

/// exp(phi): the unit quaternion of the rotation by |phi| about phi.
inline Quatd rotation_quaternion(Vec3d phi) {
  const double angle = length(phi);
  if (!(angle > 0.0)) return {};
  const SinCos half = portable_sin_cos(0.5 * angle);
  const double s = half.sin / angle;
  return {half.cos, s * phi.x, s * phi.y, s * phi.z};
}

/// log(q): the rotation vector of unit q, on the w >= 0 half (angle in [0, pi]).
inline Vec3d rotation_vector(Quatd q) {
  if (q.w < 0.0) q = {-q.w, -q.x, -q.y, -q.z};
  const double s = length(q.vec());
  if (!(s > 0.0)) return {};
  const double angle = 2.0 * portable_atan2(s, q.w);
  return (angle / s) * q.vec();
}

/// q rotated further by the small world-frame rotation vector dphi, to first order and
/// normalized: q + 1/2 [0, dphi] q (the update of Müller et al. 2020, eq. 8-9).
inline Quatd rotate_by_small(Quatd q, Vec3d dphi) {
  const Quatd d = Quatd{0.0, dphi.x, dphi.y, dphi.z} * q;
  return normalized({q.w + 0.5 * d.w, q.x + 0.5 * d.x, q.y + 0.5 * d.y, q.z + 0.5 * d.z});
}

}  // namespace seiche::rigid
