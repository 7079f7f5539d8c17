// Anisotropic surface (Yu & Turk 2013) and the ellipsoid rasterizer behind it: geometry of a
// resting block, a thin sheet and isolated particles, robustness, and thread-count determinism.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetMeasure.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

// The headers are internal to seiche_export (core/export/src).
#include "../core/export/src/anisotropic_surface.hpp"
#include "../core/export/src/ellipsoid_rasterizer.hpp"
#include "seiche/thread_count.hpp"

namespace {

using openvdb::Vec3d;
using openvdb::Vec3f;
using seiche::exporting::anisotropic_level_set;
using seiche::exporting::Ellipsoid;
using seiche::exporting::rasterize_ellipsoids;

constexpr float kSpacing = 0.02f;
constexpr float kVoxel = 0.5f * kSpacing;  // the exporter's default voxel size
constexpr float kRadius = kSpacing;        // interior sphere radius (the isotropic particle radius)
constexpr float kHalfWidth = 3.0f;

openvdb::math::Transform::Ptr voxel_transform() {
  openvdb::initialize();
  return openvdb::math::Transform::createLinearTransform(double(kVoxel));
}

// nx * ny * nz particles at origin + (i + 0.5) * spacing: the box [origin, origin + n * spacing].
std::vector<Vec3f> lattice(int nx, int ny, int nz, Vec3f origin) {
  std::vector<Vec3f> p;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        p.push_back(origin + kSpacing * Vec3f(float(i) + 0.5f, float(j) + 0.5f, float(k) + 0.5f));
  return p;
}

openvdb::FloatGrid::Ptr surface_of(const std::vector<Vec3f>& positions) {
  return anisotropic_level_set(positions, kSpacing, kRadius, voxel_transform(), kHalfWidth);
}

float sample(const openvdb::FloatGrid& grid, const openvdb::Vec3d& world) {
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(grid);
  return sampler.wsSample(world);
}

// Distance t along `dir` (unit) from `start` (inside) to the first zero crossing of the
// trilinearly sampled level set, found in steps of a tenth of a voxel and linearly interpolated.
// NaN when none is found within max_t.
double zero_crossing(const openvdb::FloatGrid& grid, openvdb::Vec3d start, openvdb::Vec3d dir,
                     double max_t) {
  const double step = 0.1 * kVoxel;
  double prev = sample(grid, start);
  for (double t = step; t <= max_t; t += step) {
    const double v = sample(grid, start + t * dir);
    if (prev < 0 && v >= 0) return t - step + step * prev / (prev - v);
    prev = v;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

bool all_finite(const openvdb::FloatGrid& grid) {
  for (auto it = grid.cbeginValueAll(); it; ++it)
    if (!std::isfinite(*it)) return false;
  return true;
}

void expect_proper_level_set(const openvdb::FloatGrid& grid) {
  EXPECT_EQ(grid.getGridClass(), openvdb::GRID_LEVEL_SET);
  EXPECT_FLOAT_EQ(grid.background(), kHalfWidth * kVoxel);
  EXPECT_TRUE(all_finite(grid));
}

// (a) A resting 16^3 block: the enclosed volume is the block's, and the surface lies at the block
// boundary (half a spacing beyond the outer particle centres) at every face centre.
TEST(AnisotropicSurface, BlockVolumeAndFacesMatchTheBlock) {
  const int n = 16;
  const Vec3f origin(0.1f, 0.2f, 0.3f);
  const auto grid = surface_of(lattice(n, n, n, origin));
  expect_proper_level_set(*grid);

  const double side = n * kSpacing;
  const double volume = openvdb::tools::levelSetVolume(*grid);
  std::printf("block volume %.6g vs %.6g: %+.2f %%\n", volume, side * side * side,
              100.0 * (volume / (side * side * side) - 1.0));
  EXPECT_NEAR(volume / (side * side * side), 1.0, 0.05);  // measured -0.7 %

  const openvdb::Vec3d centre = openvdb::Vec3d(origin) + openvdb::Vec3d(0.5 * side);
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {-1.0, 1.0}) {
      openvdb::Vec3d dir(0.0);
      dir[axis] = sign;
      const double t = zero_crossing(*grid, centre, dir, side);
      std::printf("face %c%d: crossing %+.3f voxel from the block boundary\n", sign > 0 ? '+' : '-',
                  axis, (t - 0.5 * side) / kVoxel);
      EXPECT_NEAR(t, 0.5 * side, kVoxel)  // measured -0.18 voxel
          << "axis " << axis << " sign " << sign;
    }
}

// (b) Every particle is inside: negative value by trilinear sampling (block, sheet, jittered).
TEST(AnisotropicSurface, EveryParticleIsInside) {
  std::vector<Vec3f> particles = lattice(12, 12, 12, Vec3f(0.0f));
  for (const auto& p : lattice(30, 30, 1, Vec3f(0.0f, 0.0f, 0.4f))) particles.push_back(p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.15f * kSpacing, 0.15f * kSpacing);
  for (const auto& p : lattice(10, 10, 10, Vec3f(0.5f, 0.0f, 0.0f)))
    particles.push_back(p + Vec3f(jitter(rng), jitter(rng), jitter(rng)));
  const auto grid = surface_of(particles);
  expect_proper_level_set(*grid);
  float worst = -std::numeric_limits<float>::max();
  for (const auto& p : particles) worst = std::max(worst, sample(*grid, openvdb::Vec3d(p)));
  std::printf("largest value at a particle: %.3f voxel\n", worst / kVoxel);
  EXPECT_LT(worst, 0.0f);  // measured -0.76 voxel
}

// (c) A one-layer and a two-layer 30 x 30 sheet: thin (spheres of radius r would give 2 r) and
// flat on top.
TEST(AnisotropicSurface, ThinSheetIsThinAndFlat) {
  for (int layers : {1, 2}) {
    const Vec3f origin(0.0f, 0.0f, 0.1234f);  // sheet plane off the voxel lattice
    const auto grid = surface_of(lattice(30, 30, layers, origin));
    expect_proper_level_set(*grid);
    const double mid_z = origin[2] + 0.5 * layers * kSpacing;
    std::vector<double> tops, thickness;
    for (double u = 8.0; u <= 22.0; u += 0.37)  // interior, in spacings, sampling sub-voxel offsets
      for (double v = 8.0; v <= 22.0; v += 0.41) {
        const openvdb::Vec3d at(u * kSpacing, v * kSpacing, mid_z);
        const double up = zero_crossing(*grid, at, {0, 0, 1}, 4 * kSpacing);
        const double down = zero_crossing(*grid, at, {0, 0, -1}, 4 * kSpacing);
        tops.push_back(up);
        thickness.push_back(up + down);
      }
    double mean_top = 0, mean_thickness = 0, max_thickness = 0;
    for (std::size_t k = 0; k < tops.size(); ++k) {
      mean_top += tops[k] / double(tops.size());
      mean_thickness += thickness[k] / double(tops.size());
      max_thickness = std::max(max_thickness, thickness[k]);
    }
    double var = 0;
    for (double t : tops) var += (t - mean_top) * (t - mean_top) / double(tops.size());
    const double extra = (layers - 1) * kSpacing;  // centre-to-centre distance across the layers
    std::printf(
        "%d-layer sheet: thickness mean %.3f max %.3f spacing beyond the layers (spheres: %.3f); "
        "top std dev %.4f voxel\n",
        layers, (mean_thickness - extra) / kSpacing, (max_thickness - extra) / kSpacing,
        2.0 * kRadius / kSpacing, std::sqrt(var) / kVoxel);
    EXPECT_LT(max_thickness - extra, 1.0 * kSpacing);  // measured 0.79 and 0.67 spacing
    EXPECT_LT(std::sqrt(var), 0.1 * kVoxel);           // measured 0.017 and 0.022 voxel
  }
}

// (d) Isolated particles are spheres of radius `radius`.
TEST(AnisotropicSurface, IsolatedParticlesAreSpheresOfTheRadius) {
  const std::vector<Vec3f> particles{{0.0f, 0.0f, 0.0f}, {0.2f, 0.0f, 0.0f}, {0.0f, 0.2f, 0.0137f}};
  const auto grid = surface_of(particles);
  expect_proper_level_set(*grid);
  for (const auto& p : particles)
    for (const openvdb::Vec3d dir :
         {openvdb::Vec3d(1, 0, 0), openvdb::Vec3d(0, -1, 0), openvdb::Vec3d(0, 0, 1),
          openvdb::Vec3d(1, 1, 1).unitSafe(), openvdb::Vec3d(-1, 2, 0).unitSafe()}) {
      const double r = zero_crossing(*grid, openvdb::Vec3d(p), dir, 3 * kRadius);
      // Trilinear interpolation of a sphere of 2 voxels errs by up to ~h^2 / 4R = 0.125 voxel.
      EXPECT_NEAR(r, kRadius, 0.25 * kVoxel);
    }
}

// (e) Empty input, coincident particles, non-finite positions: finite values, no crash.
TEST(AnisotropicSurface, DegenerateInputsGiveFiniteGrids) {
  const auto empty = surface_of({});
  expect_proper_level_set(*empty);
  EXPECT_EQ(empty->activeVoxelCount(), 0u);

  std::vector<Vec3f> stack(100, Vec3f(0.05f, 0.05f, 0.05f));  // one point, 100 times
  stack.push_back(Vec3f(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f));
  stack.push_back(Vec3f(0.0f, std::numeric_limits<float>::infinity(), 0.0f));
  stack.push_back(Vec3f(0.0f, 0.0f, 1e30f));  // beyond the 32-bit index space: dropped
  const auto grid = surface_of(stack);
  expect_proper_level_set(*grid);
  EXPECT_NEAR(zero_crossing(*grid, {0.05, 0.05, 0.05}, {1, 0, 0}, 3 * kRadius), kRadius,
              0.1 * kVoxel);

  std::vector<Vec3f> line;  // a collinear filament: rank-one covariance
  for (int i = 0; i < 20; ++i) line.push_back(Vec3f(0.3f + float(i) * kSpacing, 0.3f, 0.3f));
  const auto filament = surface_of(line);
  expect_proper_level_set(*filament);
  EXPECT_LT(sample(*filament, {0.3 + 10 * kSpacing, 0.3, 0.3}), 0.0f);
}

// (f) Bit-identical grids with 1 and 2 TBB threads.
TEST(AnisotropicSurface, BitIdenticalAcrossThreadCounts) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> jitter(-0.2f * kSpacing, 0.2f * kSpacing);
  std::vector<Vec3f> particles;
  for (const auto& p : lattice(24, 24, 12, Vec3f(0.0f)))
    particles.push_back(p + Vec3f(jitter(rng), jitter(rng), jitter(rng)));
  for (const auto& p : lattice(40, 40, 1, Vec3f(0.0f, 0.0f, 0.5f)))
    particles.push_back(p + Vec3f(jitter(rng), jitter(rng), jitter(rng)));

  auto build = [&](int threads) {
    return seiche::run_with_threads(threads, [&] { return surface_of(particles); });
  };
  const auto one = build(1), two = build(2);
  ASSERT_EQ(one->tree().leafCount(), two->tree().leafCount());
  ASSERT_EQ(one->activeVoxelCount(), two->activeVoxelCount());
  std::size_t compared = 0;
  auto acc = two->getConstAccessor();
  for (auto it = one->cbeginValueAll(); it; ++it) {
    const float a = *it, b = acc.getValue(it.getCoord());
    ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << it.getCoord();
    ASSERT_EQ(it.isValueOn(), acc.isValueOn(it.getCoord()));
    ++compared;
  }
  EXPECT_GT(compared, 100000u);
}

// The rasterizer alone: a sphere's band holds its signed distance (exact next to the crossing,
// within the redistancing error further out), on a transform with an offset.
TEST(EllipsoidRasterizer, SphereBandIsItsSignedDistance) {
  openvdb::initialize();
  auto transform = openvdb::math::Transform::createLinearTransform(double(kVoxel));
  transform->postTranslate(Vec3d(0.0031, -0.0047, 0.0012));
  for (float radius_voxels : {2.0f, 5.0f, 12.0f}) {
    Ellipsoid sphere{Vec3f(0.123f, -0.31f, 0.07f),
                     {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                     Vec3f(radius_voxels * kVoxel)};
    const auto grid = rasterize_ellipsoids({&sphere, 1}, transform, kHalfWidth);
    expect_proper_level_set(*grid);
    double worst_near = 0, worst = 0, sum = 0;
    std::size_t count = 0;
    for (auto it = grid->cbeginValueOn(); it; ++it) {
      const double exact =
          (grid->indexToWorld(it.getCoord()) - Vec3d(sphere.center)).length() - sphere.semi_axes[0];
      const double error = std::abs(*it - exact) / kVoxel;
      if (std::abs(exact) < 0.5 * kVoxel) worst_near = std::max(worst_near, error);
      worst = std::max(worst, error);
      sum += error;
      ++count;
    }
    std::printf("sphere of %g voxels: error mean %.3f, max %.3f voxel (%.4f within half a voxel)\n",
                radius_voxels, sum / double(count), worst, worst_near);
    EXPECT_LT(worst_near, 0.01);           // shell voxels: pass 1's value, exact for a sphere
    EXPECT_LT(sum / double(count), 0.05);  // measured 0.01-0.03
    EXPECT_LT(worst, 0.4);                 // measured 0.16-0.28
  }
}

// A tilted, three-axis ellipsoid: zero on its surface, and the crossing along each axis at a_k.
TEST(EllipsoidRasterizer, TiltedEllipsoidSurfaceIsExact) {
  const Vec3f u0 = Vec3f(1.0f, 1.0f, 0.3f).unitSafe();
  const Vec3f u1 = u0.cross(Vec3f(0.0f, 0.0f, 1.0f)).unitSafe();
  const Vec3f u2 = u0.cross(u1);
  const Ellipsoid e{
      Vec3f(0.0517f, 0.0123f, -0.0271f), {u0, u1, u2}, Vec3f(9.3f, 6.1f, 4.2f) * kVoxel};
  const auto grid = rasterize_ellipsoids({&e, 1}, voxel_transform(), kHalfWidth);
  expect_proper_level_set(*grid);
  double worst = 0;
  for (double theta = 0.05; theta < std::numbers::pi; theta += 0.1)
    for (double phi = 0; phi < 2 * std::numbers::pi; phi += 0.1) {
      const Vec3d on_surface = Vec3d(e.center) +
                               e.semi_axes[0] * std::sin(theta) * std::cos(phi) * Vec3d(u0) +
                               e.semi_axes[1] * std::sin(theta) * std::sin(phi) * Vec3d(u1) +
                               e.semi_axes[2] * std::cos(theta) * Vec3d(u2);
      worst = std::max(worst, std::abs(double(sample(*grid, on_surface))) / kVoxel);
    }
  std::printf("tilted ellipsoid: largest |value| on its surface %.3f voxel\n", worst);
  EXPECT_LT(worst, 0.25);  // trilinear interpolation across a surface curved on a voxel scale
  for (int k = 0; k < 3; ++k)
    for (double sign : {-1.0, 1.0})
      EXPECT_NEAR(zero_crossing(*grid, Vec3d(e.center), sign * Vec3d(e.axes[k]), 10 * kVoxel),
                  e.semi_axes[k], 0.1 * kVoxel)
          << "axis " << k;
}

}  // namespace
