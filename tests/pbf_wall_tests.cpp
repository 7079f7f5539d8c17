// Kernel layer: the density a wall lends to fluid particles next to it (pbf_walls.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "seiche/kernels/pbf_walls.hpp"
#include "seiche/kernels/sph_kernels.hpp"

using namespace seiche::kernels;

TEST(PbfWalls, FractionIsTheKernelIntegralBeyondThePlane) {
  const float h = 0.1f;
  EXPECT_NEAR(wall_density_fraction(0.0f, h), 0.5f, 1e-6f);  // half the support behind the wall
  EXPECT_EQ(wall_density_fraction(h, h), 0.0f);
  EXPECT_EQ(wall_density_fraction(2 * h, h), 0.0f);
  // Against a direct numerical integral of poly6 over the half-space z > d.
  const SphKernel k(h);
  for (float d : {0.01f, 0.03f, 0.05f, 0.08f}) {
    double sum = 0.0;
    const int n = 400;
    const double step = h / n;
    for (int iz = 0; iz < n; ++iz) {
      const double z = d + (iz + 0.5) * step * (1.0 - d / h);  // z in (d, h)
      const double dz = step * (1.0 - d / h);
      for (int ir = 0; ir < n; ++ir) {
        const double r = (ir + 0.5) * step;
        sum += k.poly6(float(z * z + r * r)) * 2.0 * M_PI * r * step * dz;
      }
    }
    EXPECT_NEAR(wall_density_fraction(d, h), sum, 2e-3) << "d = " << d;
  }
}

TEST(PbfWalls, SlopeIsTheDerivativeOfTheFraction) {
  const float h = 0.1f;
  for (float d : {0.0f, 0.02f, 0.05f, 0.09f}) {
    const float e = 1e-4f;
    const float fd = (wall_density_fraction(d + e, h) - wall_density_fraction(std::max(d - e, 0.0f), h)) /
                     (d + e - std::max(d - e, 0.0f));
    EXPECT_NEAR(wall_density_slope(d, h), fd, 2e-2f * std::abs(fd) + 1e-3f) << "d = " << d;
    EXPECT_LE(wall_density_slope(d, h), 0.0f);
  }
  EXPECT_EQ(wall_density_slope(h, h), 0.0f);
}
