// sin, cos and atan2 in double precision from + - * / and sqrt only, evaluated in a fixed order,
// so that a rigid body's bits are the same on every machine. The C library's are not: glibc picks
// an FMA variant of sin, cos and atan2 at load time on a CPU with FMA (x86-64) and another
// elsewhere, and another libm may round differently still. Accuracy: a few units in the last place
// (tests/rigid_body_tests.cpp compares with std::sin, cos and atan2); the range reduction is exact
// for |x| < 2^20 pi/2, beyond which sin and cos lose accuracy (the bodies use half rotation angles,
// at most pi).
//
//   sin, cos  x = k pi/2 + r with k = nearest integer to x 2/pi and |r| <= pi/4 (Cody and Waite:
//             pi/2 split into a 33-bit head, whose product with k is exact, and a tail); sin r
//             and cos r by their Taylor series to r^17 and r^18 (the next terms are below 2^-53
//             relative for |r| <= pi/4), Horner in r^2; the quadrant k mod 4 picks +-sin or +-cos.
//   atan2     t = min(|x|, |y|) / max(|x|, |y|) in [0, 1]; atan t = 4 atan u with u from two
//             halvings, atan t = 2 atan(t / (1 + sqrt(1 + t^2))), so u <= tan(pi/16) < 0.2;
//             atan u by its Taylor series to u^23 (the next term is below 2^-60 relative); then
//             the octant: pi/2 - a where |y| > |x|, pi - a where x < 0, the sign of y. atan2(0, 0)
//             is 0; a NaN argument gives NaN.
#pragma once

#include <cmath>

namespace seiche::rigid {

namespace portable_trig_detail {

inline constexpr double kPi = 3.141592653589793;
inline constexpr double kHalfPi = 1.5707963267948966;
inline constexpr double kTwoOverPi = 0.6366197723675814;
inline constexpr double kHalfPiHead = 1.57079632673412561417;   // 33 bits: k * head is exact
inline constexpr double kHalfPiTail = 6.07710050650619224932e-11;  // pi/2 - head, to double

// sin r and cos r for |r| <= pi/4: the Taylor coefficients (-1)^k / (2k+1)! and (-1)^k / (2k)!.
inline double sin_near_zero(double r) {
  const double r2 = r * r;
  double p = 2.8114572543455206e-15;
  p = p * r2 - 7.647163731819816e-13;
  p = p * r2 + 1.6059043836821613e-10;
  p = p * r2 - 2.505210838544172e-08;
  p = p * r2 + 2.7557319223985893e-06;
  p = p * r2 - 0.0001984126984126984;
  p = p * r2 + 0.008333333333333333;
  p = p * r2 - 0.16666666666666666;
  return r + r * (p * r2);
}
inline double cos_near_zero(double r) {
  const double r2 = r * r;
  double p = -1.5619206968586225e-16;
  p = p * r2 + 4.779477332387385e-14;
  p = p * r2 - 1.1470745597729725e-11;
  p = p * r2 + 2.08767569878681e-09;
  p = p * r2 - 2.755731922398589e-07;
  p = p * r2 + 2.48015873015873e-05;
  p = p * r2 - 0.001388888888888889;
  p = p * r2 + 0.041666666666666664;
  p = p * r2 - 0.5;
  return 1.0 + p * r2;
}
// atan u for |u| <= 0.2: the Taylor coefficients (-1)^k / (2k + 1).
inline double atan_near_zero(double u) {
  const double u2 = u * u;
  double p = -0.043478260869565216;
  p = p * u2 + 0.047619047619047616;
  p = p * u2 - 0.05263157894736842;
  p = p * u2 + 0.058823529411764705;
  p = p * u2 - 0.06666666666666667;
  p = p * u2 + 0.07692307692307693;
  p = p * u2 - 0.09090909090909091;
  p = p * u2 + 0.1111111111111111;
  p = p * u2 - 0.14285714285714285;
  p = p * u2 + 0.2;
  p = p * u2 - 0.3333333333333333;
  return u + u * (p * u2);
}

}  // namespace portable_trig_detail

struct SinCos {
  double sin = 0.0;
  double cos = 1.0;
};

/// sin x and cos x, the same bits everywhere (see the top of this file).
inline SinCos portable_sin_cos(double x) {
  using namespace portable_trig_detail;
  const double k = std::nearbyint(x * kTwoOverPi);  // an IEEE operation: exact, the same everywhere
  const double r = (x - k * kHalfPiHead) - k * kHalfPiTail;
  const double s = sin_near_zero(r), c = cos_near_zero(r);
  const double quadrant = k - 4.0 * std::floor(k * 0.25);  // k mod 4, in {0, 1, 2, 3}
  if (quadrant == 0.0) return {s, c};
  if (quadrant == 1.0) return {c, -s};
  if (quadrant == 2.0) return {-s, -c};
  if (quadrant == 3.0) return {-c, s};
  return {x - x, x - x};  // x is NaN or infinite: NaN
}

/// atan2(y, x) in [-pi, pi], the same bits everywhere (see the top of this file).
inline double portable_atan2(double y, double x) {
  using namespace portable_trig_detail;
  const double ax = std::fabs(x), ay = std::fabs(y);
  if (std::isnan(x) || std::isnan(y)) return x + y;
  if (ax == 0.0 && ay == 0.0) return 0.0;
  const bool steep = ay > ax;
  const double t = steep ? ax / ay : ay / ax;  // in [0, 1]; both infinite: NaN, as the result
  const double t1 = t / (1.0 + std::sqrt(1.0 + t * t));
  const double u = t1 / (1.0 + std::sqrt(1.0 + t1 * t1));
  double a = 4.0 * atan_near_zero(u);
  if (steep) a = kHalfPi - a;
  if (x < 0.0) a = kPi - a;
  return y < 0.0 ? -a : a;
}

}  // namespace seiche::rigid
