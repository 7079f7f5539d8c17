#include "seiche/kernels/pbf_density.hpp"

#include <cmath>

#include <tbb/parallel_for.h>

#include "simd.hpp"

namespace seiche::kernels {

using namespace simd;

namespace {

constexpr std::size_t kGrain = 256;
constexpr float kCoincident = 1e-12f;  // r^2 below this * h^2: no gradient direction

// Scalar parameters derived once per call.
struct Derived {
  SphKernel kernel;
  float volume;     // m / rho0
  float inv_w_dq;   // 1 / W(dq h)
  explicit Derived(const PbfParams& p)
      : kernel(p.h), volume(p.mass / p.rest_density), inv_w_dq(0.0f) {
    const float dq = p.tensile_dq * p.h;
    const float w_dq = kernel.poly6(dq * dq);
    inv_w_dq = w_dq > 0.0f ? 1.0f / w_dq : 0.0f;
  }
};

float integer_power(float x, int n) {
  float r = x;
  for (int k = 1; k < n; ++k) r *= x;
  return r;
}
Floats integer_power(const Floats& x, int n) {
  Floats r = x;
  for (int k = 1; k < n; ++k) r *= x;
  return r;
}

// The spiky gradient factor dW/dr / r and the poly6 value for one batch of neighbor offsets.
struct PairTerms {
  Floats grad_over_r, w;
};
inline PairTerms pair_terms(const SphKernel& k, const Floats& r2, const Mask& valid) {
  const Floats h2(k.h2);
  const Mask in_range = valid & (r2 < h2);
  const Mask has_direction = in_range & (r2 > Floats(kCoincident * k.h2));
  const Floats r = xsimd::sqrt(xsimd::max(r2, Floats(kCoincident * k.h2)));
  const Floats t = Floats(k.h) - r;
  const Floats grad = Floats(k.spiky_coeff) * t * t / r;
  const Floats s = xsimd::max(h2 - r2, Floats(0.0f));
  return {xsimd::select(has_direction, grad, Floats(0.0f)),
          xsimd::select(in_range, s * s * s, Floats(0.0f))};  // poly6 without its coefficient
}

}  // namespace

double lattice_kernel_sum(float spacing, float h) {
  const SphKernel k(h);
  const int reach = int(std::ceil(h / spacing));
  double sum = 0.0;
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= reach; ++c) {
        const double r2 = double(spacing) * spacing * (a * a + b * b + c * c);
        sum += k.poly6(float(r2));
      }
  return sum;
}

double lattice_lambda_denominator(float spacing, float h) {
  const SphKernel k(h);
  const double volume = 1.0 / lattice_kernel_sum(spacing, h);
  const int reach = int(std::ceil(h / spacing));
  double sum = 0.0;  // sum_j |V grad W_ij|^2; the self term |V sum_j grad W_ij|^2 is 0 by symmetry
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= reach; ++c) {
        const double r2 = double(spacing) * spacing * (a * a + b * b + c * c);
        const double g = k.spiky_grad_over_r(float(r2)) * std::sqrt(r2);
        sum += volume * volume * g * g;
      }
  return sum;
}

void pbf_density_lambda(const Float4* pos, NeighborSpan nbr, std::size_t n, const PbfParams& prm,
                        float* density, float* lambda) {
  const Derived d(prm);
  const float self_w = d.kernel.h2 * d.kernel.h2 * d.kernel.h2;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const auto& range) {
    const Floats lanes = lane_index();
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const std::uint32_t begin = nbr.offsets[i], count = nbr.offsets[i + 1] - begin;
      const std::uint32_t* list = nbr.indices + begin;
      const Floats xi(pos[i].x), yi(pos[i].y), zi(pos[i].z);
      Floats w_sum(0.0f), gx(0.0f), gy(0.0f), gz(0.0f), g2(0.0f);
      for (std::size_t k = 0; k < count; k += kLanes) {
        const Mask valid = lanes < Floats(float(count - k));
        const Gathered4 pj = gather4(pos, load_indices(list, count, k, std::int32_t(i)));
        const Floats dx = xi - pj.x, dy = yi - pj.y, dz = zi - pj.z;
        const Floats r2 = dx * dx + dy * dy + dz * dz;
        const PairTerms t = pair_terms(d.kernel, r2, valid);
        w_sum += t.w;
        gx += t.grad_over_r * dx;
        gy += t.grad_over_r * dy;
        gz += t.grad_over_r * dz;
        g2 += t.grad_over_r * t.grad_over_r * r2;
      }
      const float rho = prm.mass * d.kernel.poly6_coeff * (self_w + xsimd::hadd(w_sum));
      const float C = std::max(rho / prm.rest_density - 1.0f, 0.0f);
      const float sx = d.volume * xsimd::hadd(gx), sy = d.volume * xsimd::hadd(gy),
                  sz = d.volume * xsimd::hadd(gz);
      const float denom = sx * sx + sy * sy + sz * sz +
                          d.volume * d.volume * xsimd::hadd(g2) + prm.epsilon;
      density[i] = rho;
      lambda[i] = denom > 0.0f ? -C / denom : 0.0f;
    }
  });
}

void pbf_apply_correction(const Float4* pos_lambda, NeighborSpan nbr, std::size_t n,
                          const PbfParams& prm, float* px, float* py, float* pz) {
  const Derived d(prm);
  const bool tensile = prm.tensile_k > 0.0f && d.inv_w_dq > 0.0f;
  const float w_scale = d.kernel.poly6_coeff * d.inv_w_dq;  // W(r) / W(dq) = s^3 * this
  const float tensile_k = prm.tensile_k * prm.lambda_scale;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const auto& range) {
    const Floats lanes = lane_index();
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const std::uint32_t begin = nbr.offsets[i], count = nbr.offsets[i + 1] - begin;
      const std::uint32_t* list = nbr.indices + begin;
      const Float4 pi = pos_lambda[i];
      const Floats xi(pi.x), yi(pi.y), zi(pi.z), lambda_i(pi.w);
      Floats sx(0.0f), sy(0.0f), sz(0.0f);
      for (std::size_t k = 0; k < count; k += kLanes) {
        const Mask valid = lanes < Floats(float(count - k));
        const Gathered4 pj = gather4(pos_lambda, load_indices(list, count, k, std::int32_t(i)));
        const Floats dx = xi - pj.x, dy = yi - pj.y, dz = zi - pj.z;
        const Floats r2 = dx * dx + dy * dy + dz * dz;
        const PairTerms t = pair_terms(d.kernel, r2, valid);
        Floats scale = lambda_i + pj.w;
        if (tensile)
          scale -= Floats(tensile_k) * integer_power(t.w * Floats(w_scale), prm.tensile_n);
        const Floats f = scale * t.grad_over_r;
        sx += f * dx;
        sy += f * dy;
        sz += f * dz;
      }
      px[i] += d.volume * xsimd::hadd(sx);
      py[i] += d.volume * xsimd::hadd(sy);
      pz[i] += d.volume * xsimd::hadd(sz);
    }
  });
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
    const double rho = prm.mass * w_sum;
    const double C = std::max(rho / prm.rest_density - 1.0, 0.0);
    const double V = d.volume;
    const double denom = V * V * (gx * gx + gy * gy + gz * gz + g2) + prm.epsilon;
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
      if (prm.tensile_k > 0.0f && d.inv_w_dq > 0.0f)
        scale -= double(prm.tensile_k) * prm.lambda_scale *
                 integer_power(d.kernel.poly6(r2) * d.inv_w_dq, prm.tensile_n);
      const double f = scale * d.kernel.spiky_grad_over_r(r2);
      sx += f * dx;
      sy += f * dy;
      sz += f * dz;
    }
    px[i] += float(d.volume * sx);
    py[i] += float(d.volume * sy);
    pz[i] += float(d.volume * sz);
  }
}

}  // namespace seiche::kernels
