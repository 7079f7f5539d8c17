// SPH smoothing kernels of Position Based Fluids (Müller et al. 2003, as used by Macklin &
// Müller 2013), with support radius h:
//   poly6        W(r)    = 315 / (64 pi h^9) (h^2 - r^2)^3            for r < h, else 0
//   spiky grad   dW(r)/dr = -45 / (pi h^6) (h - r)^2                  for 0 < r < h, else 0
//                grad W(d) = dW/dr * d / |d|   (d = p_i - p_j; 0 at d = 0: no direction)
// poly6 for densities (smooth at r = 0), spiky for gradients (does not vanish at r -> 0, so
// close particles still push apart).
#pragma once

#include <cmath>
#include <numbers>

namespace seiche::kernels {

struct SphKernel {
  float h = 1.0f;
  float h2 = 1.0f;
  float poly6_coeff = 0.0f;  // 315 / (64 pi h^9)
  float spiky_coeff = 0.0f;  // -45 / (pi h^6)

  explicit SphKernel(float radius)
      : h(radius),
        h2(radius * radius),
        poly6_coeff(float(315.0 / (64.0 * std::numbers::pi * std::pow(double(radius), 9)))),
        spiky_coeff(float(-45.0 / (std::numbers::pi * std::pow(double(radius), 6)))) {}

  float poly6(float r2) const {
    if (r2 >= h2) return 0.0f;
    const float t = h2 - r2;
    return poly6_coeff * t * t * t;
  }
  /// dW/dr divided by r: multiply with d = p_i - p_j to get grad W. 0 outside (0, h).
  float spiky_grad_over_r(float r2) const {
    if (r2 >= h2 || r2 <= 1e-12f * h2) return 0.0f;  // coincident: no direction
    const float r = std::sqrt(r2);
    const float t = h - r;
    return spiky_coeff * t * t / r;
  }
};

}  // namespace seiche::kernels
