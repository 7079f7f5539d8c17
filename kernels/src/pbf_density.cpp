#include "seiche/kernels/pbf_density.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "seiche/kernels/pbf_walls.hpp"
#include "simd.hpp"

namespace seiche::kernels {

using namespace simd;

namespace {

constexpr std::size_t kGrain = 256 / kLanes;  // groups of kLanes particles
constexpr float kCoincident = 1e-12f;  // r^2 below this * h^2: no gradient direction
constexpr std::size_t kPrefetchGroups = 4;   // neighbor lists prefetched this many groups ahead

float integer_power(float x, int n) {  // n >= 1 (the scalar reference)
  float r = x;
  for (int k = 1; k < n; ++k) r *= x;
  return r;
}

// Scalar parameters derived once per call.
struct Derived {
  SphKernel kernel;
  float volume;        // m / rho0
  float inv_w_dq;      // 1 / W(dq h)
  float rest_power;    // u_s^n = (W(s) / W(dq h))^n, 0 without a rest distance
  float tensile_norm;  // 1 / (1 - u_s^n); 0 (no s_corr) where u_s >= 1
  explicit Derived(const PbfParams& p)
      : kernel(p.h), volume(p.mass / p.rest_density), inv_w_dq(0.0f), rest_power(0.0f),
        tensile_norm(0.0f) {
    const float dq = p.tensile_dq * p.h;
    const float w_dq = kernel.poly6(dq * dq);
    inv_w_dq = w_dq > 0.0f ? 1.0f / w_dq : 0.0f;
    const float s = p.tensile_rest_distance;
    if (s > 0.0f) rest_power = integer_power(kernel.poly6(s * s) * inv_w_dq, p.tensile_n);
    tensile_norm = rest_power < 1.0f ? 1.0f / (1.0f - rest_power) : 0.0f;
  }
  bool tensile(const PbfParams& p) const { return p.tensile_k > 0.0f && inv_w_dq > 0.0f && tensile_norm > 0.0f; }
};
template <int N, class T>
T integer_power(const T& x) {  // N >= 1, by repeated squaring
  if constexpr (N == 1) {
    return x;
  } else {
    const T half = integer_power<N / 2>(x);
    if constexpr (N % 2 == 0) return half * half;
    else return half * half * x;
  }
}

// Per-pair kernel terms without their coefficients (applied once per particle at the end):
//   grad = (h - r)^2 / r    spiky dW/dr / r = spiky_coeff * grad; 0 outside (0, h) and for
//                           coincident particles (no direction)
//   s    = max(h^2 - r^2, 0) poly6 W = poly6_coeff * s^3
template <class T>
struct PairTerms {
  T grad, s;
};
struct PairConstants {
  Floats h, h2, r2_min, far, zero;
  explicit PairConstants(const SphKernel& k)
      : h(k.h), h2(k.h2), r2_min(kCoincident * k.h2), far(4.0f * k.h2), zero(0.0f) {}
};
template <class T>
SEICHE_INLINE inline PairTerms<T> pair_terms(const PairConstants& c, const T& r2) {
  // r and (h - r)^2 / r from the correctly rounded sqrt and division: the same bits on every
  // instruction set (a hardware 1/sqrt estimate, even refined by a Newton step, is not; see
  // seiche/simd/batch.hpp).
  const T r = xsimd::sqrt(xsimd::max(r2, c.r2_min));
  const T t = xsimd::max(c.h - r, c.zero);  // h - r, 0 past h
  return {keep_if(r2 > c.r2_min, t * t / r), xsimd::max(c.h2 - r2, c.zero)};
}

// Offsets and squared distance from the group's particles to their slot neighbors; lanes past
// their list (masked) get r^2 = 4 h^2, where every kernel term is 0.
template <class T>
struct PairGeometry {
  T dx, dy, dz, r2;
};
template <class Masked>
SEICHE_INLINE inline PairGeometry<Floats> pair_geometry(const PairConstants& c, const Gathered4& pi,
                                                        const Gathered4& pj, Masked,
                                                        const Mask& valid) {
  const Floats dx = pi.x - pj.x, dy = pi.y - pj.y, dz = pi.z - pj.z;
  Floats r2 = multiply_add(dz, dz, multiply_add(dy, dy, dx * dx));
  if constexpr (Masked::value) r2 = xsimd::select(valid, r2, c.far);
  return {dx, dy, dz, r2};
}

// The domain walls' share of a particle's density and its gradient (pbf_walls.hpp), for floats
// and for batches. Per axis a, f_a = scale (f(d_lo) + f(d_hi)); the walls of different axes
// overlap in edges and corners, so they combine as if the kernel were separable:
//   F = 1 - prod_a (1 - f_a),   dF/dp_a = f_a' prod_{b != a} (1 - f_b)
// (a plain sum would count the edges and corner twice: about +10 % density at a box corner).
template <class T>
struct WallSum {
  T fraction, gx, gy, gz;
};
template <class T, class Max, class Min>
SEICHE_INLINE inline WallSum<T> domain_walls(const PbfParams& prm, const T& x, const T& y,
                                             const T& z, Max max_fn, Min min_fn) {
  const T* p[3] = {&x, &y, &z};
  T f[3], g[3];
  for (int a = 0; a < 3; ++a) {
    const auto lo = wall_term<T>(*p[a] - T(prm.wall_min[a]), prm.h, max_fn, min_fn);  // n = +e_a
    const auto hi = wall_term<T>(T(prm.wall_max[a]) - *p[a], prm.h, max_fn, min_fn);  // n = -e_a
    f[a] = T(prm.wall_scale) * (lo.fraction + hi.fraction);
    g[a] = T(prm.wall_scale) * (lo.slope - hi.slope);
  }
  const T in0 = T(1.0f) - f[0], in1 = T(1.0f) - f[1], in2 = T(1.0f) - f[2];
  return {T(1.0f) - in0 * in1 * in2, g[0] * in1 * in2, g[1] * in0 * in2, g[2] * in0 * in1};
}
inline WallSum<Floats> domain_walls(const PbfParams& prm, const Gathered4& p) {
  return domain_walls<Floats>(
      prm, p.x, p.y, p.z, [](const Floats& a, const Floats& b) { return xsimd::max(a, b); },
      [](const Floats& a, const Floats& b) { return xsimd::min(a, b); });
}
// Whether any lane of the group is within h of a wall. If none is, every wall term is exactly 0
// (u = 1 in wall_term: fraction and slope are 0), so the group skips them: in a large domain
// most groups do. The test uses wall_term's own arithmetic for u, so skipping changes no bit.
SEICHE_INLINE inline bool near_a_wall(const PbfParams& prm, const Gathered4& p) {
  const Floats inv_h(1.0f / prm.h), one(1.0f);
  const Floats* c[3] = {&p.x, &p.y, &p.z};
  Mask near(false);
  for (int a = 0; a < 3; ++a) {
    near = near | ((*c[a] - Floats(prm.wall_min[a])) * inv_h < one);
    near = near | ((Floats(prm.wall_max[a]) - *c[a]) * inv_h < one);
  }
  return xsimd::any(near);
}
inline WallSum<float> domain_walls(const PbfParams& prm, const Float4& p) {
  return domain_walls<float>(
      prm, p.x, p.y, p.z, [](float a, float b) { return std::max(a, b); },
      [](float a, float b) { return std::min(a, b); });
}

}  // namespace

namespace {
// Calls f(r^2) for every point of an ideal lattice of the given spacing within the kernel's
// reach of the origin (the origin included).
template <class F>
void for_each_lattice_point(float spacing, float h, F&& f) {
  const int reach = int(std::ceil(h / spacing));
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= reach; ++c) f(double(spacing) * spacing * (a * a + b * b + c * c));
}
}  // namespace

double lattice_kernel_sum(float spacing, float h) {
  const SphKernel k(h);
  double sum = 0.0;
  for_each_lattice_point(spacing, h, [&](double r2) { sum += k.poly6(float(r2)); });
  return sum;
}

double lattice_wall_share(float spacing, float h) {
  // The lattice points behind a wall for a particle half a spacing in front of it: those whose
  // height (c + 1/2) spacing is below 0, i.e. c <= -1.
  const SphKernel k(h);
  const int reach = int(std::ceil(h / spacing));
  double behind = 0.0;
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= -1; ++c)
        behind += k.poly6(float(double(spacing) * spacing * (a * a + b * b + c * c)));
  return behind / lattice_kernel_sum(spacing, h);
}

double lattice_lambda_denominator(float spacing, float h) {
  const SphKernel k(h);
  const double volume = 1.0 / lattice_kernel_sum(spacing, h);
  double sum = 0.0;  // sum_j |V grad W_ij|^2; the self term |V sum_j grad W_ij|^2 is 0 by symmetry
  for_each_lattice_point(spacing, h, [&](double r2) {
    const double g = k.spiky_grad_over_r(float(r2)) * std::sqrt(r2);
    sum += volume * volume * g * g;
  });
  return sum;
}

void pbf_density_lambda(const Float4* pos, NeighborSpan nbr, std::size_t n, const PbfParams& prm,
                        float* density, float* lambda) {
  const Derived d(prm);
  const float self_s3 = d.kernel.h2 * d.kernel.h2 * d.kernel.h2;
  const float rho_scale = prm.mass * d.kernel.poly6_coeff;
  const float grad_scale = d.volume * d.kernel.spiky_coeff;  // V spiky_coeff
  const std::size_t groups = (n + kLanes - 1) / kLanes;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, kGrain), [&](const auto& range) {
    const PairConstants c(d.kernel);
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      prefetch_lists(nbr, (g + kPrefetchGroups) * kLanes, (g + kPrefetchGroups + 1) * kLanes, n);
      const NeighborGroup group(nbr, g * kLanes, n);
      const Gathered4 pi = group.own(pos);
      Floats w_sum(0.0f), gx(0.0f), gy(0.0f), gz(0.0f), g2(0.0f);
      for_each_slot(group, pos, [&](const Gathered4& pj, auto masked, const Mask& valid)
                                    SEICHE_INLINE {
        const auto q = pair_geometry(c, pi, pj, masked, valid);
        const auto t = pair_terms(c, q.r2);
        accumulate(w_sum, t.s * t.s, t.s);
        accumulate(gx, t.grad, q.dx);
        accumulate(gy, t.grad, q.dy);
        accumulate(gz, t.grad, q.dz);
        accumulate(g2, t.grad * t.grad, q.r2);
      });
      Floats rho = Floats(rho_scale) * (Floats(self_s3) + w_sum);
      Floats sx = Floats(grad_scale) * gx, sy = Floats(grad_scale) * gy, sz = Floats(grad_scale) * gz;
      if (prm.walls && near_a_wall(prm, pi)) {
        const WallSum<Floats> wall = domain_walls(prm, pi);
        rho += Floats(prm.rest_density) * wall.fraction;
        sx += wall.gx, sy += wall.gy, sz += wall.gz;
      }
      if (prm.boundary != nullptr) {
        const Gathered4 b = group.own(prm.boundary);
        rho += b.w;
        sx += b.x, sy += b.y, sz += b.z;
      }
      const Floats C = xsimd::max(rho / Floats(prm.rest_density) - Floats(1.0f), Floats(0.0f));
      const Floats denom = sx * sx + sy * sy + sz * sz +
                           Floats(grad_scale * grad_scale) * g2 + Floats(prm.epsilon);
      group.store(density, rho);
      group.store(lambda, xsimd::select(denom > Floats(0.0f), negate(C) / denom, Floats(0.0f)));
    }
  });
}

namespace {

// Pass 2 with the artificial-pressure exponent N fixed at compile time (N = 0: no s_corr).
template <int N>
void apply_correction(const Float4* pos_lambda, NeighborSpan nbr, std::size_t n,
                      const PbfParams& prm, float* px, float* py, float* pz) {
  const Derived d(prm);
  const float grad_scale = d.volume * d.kernel.spiky_coeff;
  const float w_scale = d.kernel.poly6_coeff * d.inv_w_dq;  // W(r) / W(dq) = s^3 * this
  const float tensile_k = prm.tensile_k * prm.lambda_scale * d.tensile_norm;
  const std::size_t groups = (n + kLanes - 1) / kLanes;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, kGrain), [&](const auto& range) {
    const PairConstants c(d.kernel);
    const Floats w_scale_b(w_scale), tensile_k_b(tensile_k), rest_power_b(d.rest_power);
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      prefetch_lists(nbr, (g + kPrefetchGroups) * kLanes, (g + kPrefetchGroups + 1) * kLanes, n);
      const NeighborGroup group(nbr, g * kLanes, n);
      const Gathered4 pi = group.own(pos_lambda);
      Floats sx(0.0f), sy(0.0f), sz(0.0f);
      for_each_slot(group, pos_lambda, [&](const Gathered4& pj, auto masked, const Mask& valid)
                                           SEICHE_INLINE {
        const auto q = pair_geometry(c, pi, pj, masked, valid);
        const auto t = pair_terms(c, q.r2);
        Floats scale = pi.w + pj.w;
        if constexpr (N > 0)
          scale = mul_sub_from(
              tensile_k_b,
              xsimd::max(integer_power<N>(t.s * t.s * t.s * w_scale_b) - rest_power_b, c.zero),
              scale);
        const Floats f = scale * t.grad;
        accumulate(sx, f, q.dx);
        accumulate(sy, f, q.dy);
        accumulate(sz, f, q.dz);
      });
      sx *= Floats(grad_scale), sy *= Floats(grad_scale), sz *= Floats(grad_scale);
      // lambda_i f'(d) n: the wall's part of the particle's own constraint
      if (prm.walls && near_a_wall(prm, pi)) {
        const WallSum<Floats> wall = domain_walls(prm, pi);
        const Floats push = pi.w;
        sx += push * wall.gx, sy += push * wall.gy, sz += push * wall.gz;
      }
      group.store(px, group.load(px) + sx);
      group.store(py, group.load(py) + sy);
      group.store(pz, group.load(pz) + sz);
    }
  });
}

}  // namespace

void pbf_apply_correction(const Float4* pos_lambda, NeighborSpan nbr, std::size_t n,
                          const PbfParams& prm, float* px, float* py, float* pz) {
  const bool tensile = Derived(prm).tensile(prm);
  switch (tensile ? prm.tensile_n : 0) {
    case 0: return apply_correction<0>(pos_lambda, nbr, n, prm, px, py, pz);
    case 1: return apply_correction<1>(pos_lambda, nbr, n, prm, px, py, pz);
    case 2: return apply_correction<2>(pos_lambda, nbr, n, prm, px, py, pz);
    case 3: return apply_correction<3>(pos_lambda, nbr, n, prm, px, py, pz);
    case 4: return apply_correction<4>(pos_lambda, nbr, n, prm, px, py, pz);
    case 5: return apply_correction<5>(pos_lambda, nbr, n, prm, px, py, pz);
    case 6: return apply_correction<6>(pos_lambda, nbr, n, prm, px, py, pz);
    case 7: return apply_correction<7>(pos_lambda, nbr, n, prm, px, py, pz);
    default: return apply_correction<8>(pos_lambda, nbr, n, prm, px, py, pz);
  }
}

void pbf_density_lambda_reference(const Float4* pos, NeighborSpan nbr, std::size_t n,
                                  const PbfParams& prm, float* density, float* lambda) {
  const Derived d(prm);
  for (std::size_t i = 0; i < n; ++i) {
    double w_sum = d.kernel.poly6(0.0f), gx = 0, gy = 0, gz = 0, g2 = 0;
    for (std::uint32_t k = nbr.offsets[i]; k < nbr.offsets[i + 1]; ++k) {
      const Float4 pj = pos[nbr.indices[k]];
      const float dx = pos[i].x - pj.x, dy = pos[i].y - pj.y, dz = pos[i].z - pj.z;
      const float r2 = dx * dx + dy * dy + dz * dz;
      const float g = d.kernel.spiky_grad_over_r(r2);
      w_sum += d.kernel.poly6(r2);
      gx += g * dx;
      gy += g * dy;
      gz += g * dz;
      g2 += double(g) * g * r2;
    }
    double rho = prm.mass * w_sum;
    const double V = d.volume;
    double sx = V * gx, sy = V * gy, sz = V * gz;
    if (prm.walls) {
      const WallSum<float> wall = domain_walls(prm, pos[i]);
      rho += double(prm.rest_density) * wall.fraction;
      sx += wall.gx, sy += wall.gy, sz += wall.gz;
    }
    if (prm.boundary != nullptr) {
      const Float4 b = prm.boundary[i];
      rho += double(b.w);
      sx += b.x, sy += b.y, sz += b.z;
    }
    const double C = std::max(rho / prm.rest_density - 1.0, 0.0);
    const double denom = sx * sx + sy * sy + sz * sz + V * V * g2 + prm.epsilon;
    density[i] = float(rho);
    lambda[i] = denom > 0.0 ? float(-C / denom) : 0.0f;
  }
}

void pbf_apply_correction_reference(const Float4* pos_lambda, NeighborSpan nbr, std::size_t n,
                                    const PbfParams& prm, float* px, float* py, float* pz) {
  const Derived d(prm);
  for (std::size_t i = 0; i < n; ++i) {
    double sx = 0, sy = 0, sz = 0;
    const Float4 pi = pos_lambda[i];
    for (std::uint32_t k = nbr.offsets[i]; k < nbr.offsets[i + 1]; ++k) {
      const Float4 pj = pos_lambda[nbr.indices[k]];
      const float dx = pi.x - pj.x, dy = pi.y - pj.y, dz = pi.z - pj.z;
      const float r2 = dx * dx + dy * dy + dz * dz;
      double scale = double(pi.w) + pj.w;
      if (d.tensile(prm))
        scale -= double(prm.tensile_k) * prm.lambda_scale * d.tensile_norm *
                 std::max(double(integer_power(d.kernel.poly6(r2) * d.inv_w_dq, prm.tensile_n)) -
                              d.rest_power, 0.0);
      const double f = scale * d.kernel.spiky_grad_over_r(r2);
      sx += f * dx;
      sy += f * dy;
      sz += f * dz;
    }
    sx *= d.volume, sy *= d.volume, sz *= d.volume;
    if (prm.walls) {
      const WallSum<float> wall = domain_walls(prm, pi);
      const double push = pi.w;
      sx += push * wall.gx, sy += push * wall.gy, sz += push * wall.gz;
    }
    px[i] += float(sx);
    py[i] += float(sy);
    pz[i] += float(sz);
  }
}

}  // namespace seiche::kernels
