// The density a solid wall lends to a fluid particle next to it, so that a particle at a wall has
// the density of a particle inside the fluid (without it the wall side of its neighborhood is
// empty: near-wall particles read as too light, the fluid piles up against walls, and a hard
// impact stacks particles onto the wall plane, where one Jacobi iteration cannot undo it).
//
// The wall is a half-space treated as rest fluid: a particle at distance d = u h from the wall
// plane gains the fraction of its kernel support beyond the plane, poly6 integrated over the
// half-space z > d (the kernel integrates to 1 over all space):
//   A(z) = integral of W over the disk at height z = 315 / (256 h) (1 - (z/h)^2)^4
//   f(d) = integral_d^h A(z) dz = 315/256 [Q(1) - Q(u)],  Q(u) = u - 4/3 u^3 + 6/5 u^5 - 4/7 u^7 + u^9/9
//        = (1 - u)^5 (128 + 325 u + 345 u^2 + 175 u^3 + 35 u^4) / 256   (exactly 0 at u = 1)
//   f(0) = 1/2,  f(h) = 0,  df/dd = -315 / (256 h) (1 - u^2)^4
// In the density constraint (V-form, see pbf_density.hpp) a wall adds f(d_i) to rho_i / rho0,
// f'(d_i) n to grad_{p_i} C_i (n: the wall's normal into the fluid) and lambda_i f'(d_i) n to
// dp_i: the wall is part of the particle's own constraint only (as boundary particles are in
// SPlisHSPlasH's PBF). Mirroring the particle's pressure onto the wall (2 lambda_i f'(d_i) n)
// was tried and overshoots: the resting column gained energy. The wall does not move. A continuous half-space lends slightly more than the lattice
// layers it stands for (0.217 against 0.191 at d = spacing / 2 for h = 2 spacings), so the first
// layer rests a few percent of a spacing further from the wall than the lattice would.
#pragma once

namespace seiche::kernels {

/// Works for float and for SIMD batches (with max/min found by argument-dependent lookup).
template <class T>
struct WallTerm {
  T fraction;  ///< f(d)
  T slope;     ///< df/dd (<= 0)
};

template <class T, class Max, class Min>
inline WallTerm<T> wall_term(const T& d, float h, Max max_fn, Min min_fn) {
  const T u = min_fn(max_fn(d * T(1.0f / h), T(0.0f)), T(1.0f));  // 0 behind the plane, 1 past h
  const T v = T(1.0f) - u, v2 = v * v;
  const T poly = T(128.0f / 256.0f) +
                 u * (T(325.0f / 256.0f) + u * (T(345.0f / 256.0f) + u * (T(175.0f / 256.0f) + u * T(35.0f / 256.0f))));
  const T t = (T(1.0f) + u) * v;  // 1 - u^2
  const T t2 = t * t;
  return {v2 * v2 * v * poly, T(-315.0f / (256.0f * h)) * t2 * t2};
}

inline float wall_density_fraction(float d, float h) {
  auto mx = [](float a, float b) { return a > b ? a : b; };
  auto mn = [](float a, float b) { return a < b ? a : b; };
  return wall_term<float>(d, h, mx, mn).fraction;
}

inline float wall_density_slope(float d, float h) {
  auto mx = [](float a, float b) { return a > b ? a : b; };
  auto mn = [](float a, float b) { return a < b ? a : b; };
  return wall_term<float>(d, h, mx, mn).slope;
}

}  // namespace seiche::kernels
