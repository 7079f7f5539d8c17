// atan2 for batches and floats, with the same bits on every width and instruction set.
//
// xsimd's atan2 evaluates its polynomial with xsimd's fma, which is fused on AVX2 and not on
// AVX-512 (batch.hpp), so its results differ between the two builds. This one uses only
// correctly rounded operations and multiply_add, and the float overload runs the very same
// operations, so a scalar reference gets the bits of every lane.
//
// Method: with a = min(|x|, |y|) / max(|x|, |y|) in [0, 1],
//   atan(a) = atan(t) + pi/4 with t = (a - 1) / (a + 1)   when a > tan(pi/8)
//   atan(t) = t + t s P(s),  s = t^2 <= tan^2(pi/8)       (|t| <= tan(pi/8) either way)
// P is a degree-4 polynomial fitted to (atan(t)/t - 1)/s on that interval (weighted least squares
// on Chebyshev nodes, relative error 7e-10 before rounding the coefficients to float), so the
// result is within a few ulp of the true angle (tests/simd_tests.cpp measures it). Then
// atan2 = pi/2 - atan(a) where |y| > |x|, pi - that where x < 0, and the sign of y.
// Finite inputs only (inf/inf is NaN). atan2(y, -0) is treated as atan2(y, +0), and a zero y
// of either sign gives +0 or pi: signed zeros aside, it agrees with std::atan2.
#pragma once

#include <cmath>
#include <numbers>

#include "seiche/simd/batch.hpp"
#include "seiche/simd/intrinsics.hpp"

namespace seiche::simd {

namespace detail {

// The float twins of the batch operations atan2 uses, with their x86 semantics: abs clears the
// sign bit, min(a, b) and max(a, b) return b unless a is strictly smaller or larger (minps, maxps).
inline float select(bool m, float a, float b) { return m ? a : b; }
inline Floats select(const Mask& m, const Floats& a, const Floats& b) {
  return xsimd::select(m, a, b);
}
inline float abs(float x) { return std::fabs(x); }
inline Floats abs(const Floats& x) { return xsimd::abs(x); }
inline float min(float a, float b) { return a < b ? a : b; }
inline Floats min(const Floats& a, const Floats& b) { return xsimd::min(a, b); }
inline float max(float a, float b) { return a > b ? a : b; }
inline Floats max(const Floats& a, const Floats& b) { return xsimd::max(a, b); }

}  // namespace detail

/// The angle of (x, y) in (-pi, pi], as std::atan2(y, x) (see above for the edge cases).
template <class T>
inline T atan2(const T& y, const T& x) {
  using detail::select;
  constexpr float kPi = std::numbers::pi_v<float>;
  constexpr float kTanPiOver8 = 0.41421356f;
  const T zero(0.0f), one(1.0f);
  const T ax = detail::abs(x), ay = detail::abs(y);
  const T big = detail::max(ax, ay), small = detail::min(ax, ay);
  const T a = select(big > zero, small / select(big > zero, big, one), zero);
  const auto reduced = a > T(kTanPiOver8);
  const T t = select(reduced, (a - one) / (a + one), a);
  const T s = t * t;
  T p(-0.06083390861749649f);
  p = multiply_add(p, s, T(0.10595974326133728f));
  p = multiply_add(p, s, T(-0.14243844151496887f));
  p = multiply_add(p, s, T(0.19998489320278168f));
  p = multiply_add(p, s, T(-0.33333316445350647f));
  T r = multiply_add(t * s, p, t);
  r = select(reduced, r + T(kPi / 4.0f), r);
  r = select(ay > ax, T(kPi / 2.0f) - r, r);
  r = select(x < zero, T(kPi) - r, r);
  return select(y < zero, negate(r), r);
}

}  // namespace seiche::simd
