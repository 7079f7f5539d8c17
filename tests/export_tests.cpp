// The OpenVDB export of fluid frames: the surface's geometry on a resting block (faces, corners,
// volume), every particle inside on a lattice and on a splash, the fast surface against a
// brute-force evaluation of the same field, the file's grids, metadata, options and byte-exact
// reproducibility, the VDB Points round trip, the velocity grid, the OBJ mesh, and the
// exporter's files and errors.
#include <gtest/gtest.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointAttribute.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetMeasure.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "seiche/export/vdb_exporter.hpp"
// The surface's stages are internal to seiche_export (core/export/src).
#include "../core/export/src/fluid_surface.hpp"
#include "seiche/output_files.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/thread_count.hpp"
#include "test_temp_dir.hpp"

namespace {

using seiche::EncodedFluidFrame;
using seiche::FluidExportSettings;
using seiche::FluidParticles;

constexpr float kSpacing = 0.02f;
constexpr float kVoxel = 0.5f * kSpacing;  // the default voxel size
constexpr double kHalfWidth = 3.0;

// ---- Particles ---------------------------------------------------------------------------------

void add_particle(FluidParticles& p, double x, double y, double z,
                  openvdb::Vec3f v = openvdb::Vec3f(0.0f)) {
  p.x.push_back(float(x)), p.y.push_back(float(y)), p.z.push_back(float(z));
  p.vx.push_back(v[0]), p.vy.push_back(v[1]), p.vz.push_back(v[2]);
  p.id.push_back(std::int32_t(p.id.size()));
}

/// nx * ny * nz particles at lo + (i + 0.5) * spacing: the block [lo, lo + n * spacing].
FluidParticles block(int nx, int ny, int nz, openvdb::Vec3d lo, float spacing = kSpacing) {
  FluidParticles p;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        add_particle(p, lo[0] + (i + 0.5) * spacing, lo[1] + (j + 0.5) * spacing,
                     lo[2] + (k + 0.5) * spacing,
                     openvdb::Vec3f(0.1f * float(i), -0.2f * float(j), 0.05f * float(k)));
  return p;
}

/// A splash: a sheet one particle thick, small clusters, pairs and lone droplets, at random.
FluidParticles splash(unsigned seed) {
  FluidParticles p;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double s = kSpacing;
  for (int i = 0; i < 14; ++i)  // a wavy sheet
    for (int k = 0; k < 14; ++k)
      add_particle(p, 0.5 + i * s, 0.30 + 0.2 * s * std::sin(0.7 * i) + 0.1 * s * u(rng),
                   0.5 + k * s);
  for (int c = 0; c < 30; ++c) {  // clusters of 1 to 6 particles, 0.6 to 1.4 spacings apart
    const openvdb::Vec3d centre(0.4 + 0.5 * u(rng), 0.45 + 0.3 * u(rng), 0.4 + 0.5 * u(rng));
    const int count = 1 + c % 6;
    for (int m = 0; m < count; ++m) {
      const openvdb::Vec3d d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
      const openvdb::Vec3d q = centre + (0.6 + 0.8 * u(rng)) * s * double(m > 0) * d.unitSafe();
      add_particle(p, q[0], q[1], q[2], openvdb::Vec3f(float(u(rng)), 1.0f, 0.0f));
    }
  }
  for (int m = 0; m < 400; ++m)  // a loose spray
    add_particle(p, 0.2 + 0.4 * u(rng), 0.1 + 0.1 * u(rng), 0.2 + 0.4 * u(rng));
  return p;
}

FluidParticles concat(FluidParticles a, const FluidParticles& b) {
  for (std::size_t i = 0; i < b.size(); ++i)
    add_particle(a, b.x[i], b.y[i], b.z[i], openvdb::Vec3f(b.vx[i], b.vy[i], b.vz[i]));
  return a;
}

FluidExportSettings settings(bool surface = true, bool density = false, bool points = false,
                             bool velocity = false) {
  FluidExportSettings s;
  s.scene_name = "test";
  s.spacing = kSpacing;
  s.surface = surface, s.density = density, s.points = points, s.velocity = velocity;
  return s;
}

// ---- Reading back ------------------------------------------------------------------------------

struct Decoded {
  openvdb::GridPtrVec grids;
  openvdb::MetaMap::Ptr metadata;
  std::uint32_t last_grid_compression = 0;

  template <class GridT>
  typename GridT::Ptr get(const std::string& name) const {
    for (const auto& g : grids)
      if (g->getName() == name) return openvdb::gridPtrCast<GridT>(g);
    return nullptr;
  }
};

Decoded decode(const std::string& bytes) {
  openvdb::initialize();
  std::istringstream in(bytes, std::ios_base::in | std::ios_base::binary);
  openvdb::io::Stream stream(in, /*delayLoad=*/false);
  Decoded d;
  d.grids = *stream.getGrids();
  d.metadata = stream.getMetadata();
  d.last_grid_compression = openvdb::io::getDataCompression(in);
  return d;
}

openvdb::FloatGrid::Ptr surface_of(const FluidParticles& p, FluidExportSettings s = settings()) {
  s.surface = true;
  return decode(seiche::encode_fluid_frame(p, s, {1, 0.0}).vdb).get<openvdb::FloatGrid>("surface");
}

double sample(const openvdb::FloatGrid& grid, const openvdb::Vec3d& world) {
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(grid);
  return sampler.wsSample(world);
}

/// Distance along `dir` (unit) from `start` (inside) to the first zero crossing of the
/// trilinearly sampled level set, in steps of a twentieth of a voxel, linearly interpolated.
double zero_crossing(const openvdb::FloatGrid& grid, openvdb::Vec3d start, openvdb::Vec3d dir,
                     double max_t) {
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(grid);
  const double step = 0.05 * grid.voxelSize()[0];
  double prev = sampler.wsSample(start);
  for (double t = step; t <= max_t; t += step) {
    const double v = sampler.wsSample(start + t * dir);
    if (prev < 0 && v >= 0) return t - step + step * prev / (prev - v);
    prev = v;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// ---- Surface geometry --------------------------------------------------------------------------

// A 20 x 16 x 12 block, not aligned with the voxels: along lines through its six faces (every
// half spacing, up to one spacing from the edges) the zero crossing lies within a voxel of the
// face; through the eight corners (along the diagonals) within a voxel of the corner.
TEST(Surface, ZeroCrossingWithinAVoxelOfTheBlockFaces) {
  const openvdb::Vec3d lo(0.1037, -0.2291, 0.3113);
  const std::array<int, 3> n{20, 16, 12};
  const openvdb::Vec3d hi = lo + kSpacing * openvdb::Vec3d(n[0], n[1], n[2]);
  const auto grid = surface_of(block(n[0], n[1], n[2], lo));
  ASSERT_TRUE(grid);
  const openvdb::Vec3d centre = 0.5 * (lo + hi);
  double worst_face = 0.0, mean_face = 0.0;
  int lines = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int side = -1; side <= 1; side += 2) {
      for (double u = lo[a] + kSpacing; u <= hi[a] - kSpacing + 1e-9; u += 0.5 * kSpacing)
        for (double v = lo[b] + kSpacing; v <= hi[b] - kSpacing + 1e-9; v += 0.5 * kSpacing) {
          openvdb::Vec3d start = centre, dir(0.0);
          start[a] = u, start[b] = v;
          dir[axis] = side;
          const double face = side > 0 ? hi[axis] - centre[axis] : centre[axis] - lo[axis];
          const double t = zero_crossing(*grid, start, dir, face + 6 * kVoxel);
          ASSERT_TRUE(std::isfinite(t)) << "no crossing from " << start << " along " << dir;
          worst_face = std::max(worst_face, std::abs(t - face));
          mean_face += t - face;
          ++lines;
        }
    }
  }
  // Corners: along the diagonal from the corner particle (half a spacing in from each face).
  double worst_corner = 0.0;
  for (int c = 0; c < 8; ++c) {
    const openvdb::Vec3d dir((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
    const openvdb::Vec3d corner((c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1],
                                (c & 4) ? hi[2] : lo[2]);
    const openvdb::Vec3d particle = corner - 0.5 * kSpacing * dir;
    const double t = zero_crossing(*grid, particle, dir / std::sqrt(3.0), 4 * kSpacing);
    ASSERT_TRUE(std::isfinite(t));
    worst_corner = std::max(worst_corner, std::abs(t - (corner - particle).length()));
  }
  mean_face /= std::max(lines, 1);
  std::printf(
      "[ faces ] %d lines: crossing - face: mean %+.3f, max |.| %.3f voxels; corners: %.3f "
      "voxels\n",
      lines, mean_face / kVoxel, worst_face / kVoxel, worst_corner / kVoxel);
  EXPECT_LT(std::abs(mean_face), 0.25 * kVoxel);  // the erosion is calibrated for this (0.16)
  EXPECT_LT(worst_face, 0.5 * kVoxel);
  EXPECT_LT(worst_corner, 2.0 * kVoxel);  // corners round off (a block's edge reads c = 1/4)
}

TEST(Surface, EnclosedVolumeMatchesTheBlock) {
  for (const auto& [n, voxel] : {std::pair{std::array<int, 3>{12, 12, 12}, kVoxel},
                                 std::pair{std::array<int, 3>{24, 10, 16}, kVoxel},
                                 std::pair{std::array<int, 3>{16, 16, 16}, 0.7f * kSpacing},
                                 std::pair{std::array<int, 3>{16, 16, 16}, 0.25f * kSpacing}}) {
    FluidExportSettings s = settings();
    s.voxel_size = voxel;
    const auto grid = surface_of(block(n[0], n[1], n[2], openvdb::Vec3d(0.2, 0.3, 0.4)), s);
    const double exact = double(n[0]) * n[1] * n[2] * std::pow(double(kSpacing), 3);
    const double volume = openvdb::tools::levelSetVolume(*grid);
    std::printf("[ volume ] %dx%dx%d block, voxel %.2f spacing: %.3f %% off\n", n[0], n[1], n[2],
                double(voxel / kSpacing), 100.0 * (volume / exact - 1.0));
    EXPECT_NEAR(volume / exact, 1.0, 0.05);
  }
}

void expect_every_particle_inside(const FluidParticles& p, FluidExportSettings s,
                                  const char* what) {
  const auto grid = surface_of(p, s);
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*grid);
  int outside = 0;
  double worst = -std::numeric_limits<double>::max();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double phi = sampler.wsSample(openvdb::Vec3d(p.x[i], p.y[i], p.z[i]));
    worst = std::max(worst, phi);
    outside += !(phi < 0.0);
  }
  std::printf(
      "[ inside ] %s, voxel %.2f spacing: %zu particles, max phi at a particle %.3f voxels\n", what,
      double(s.resolved_voxel_size() / s.spacing), p.size(), worst / s.resolved_voxel_size());
  EXPECT_EQ(outside, 0) << what;
}

TEST(Surface, EveryParticleIsInside) {
  for (const float voxel : {0.0f, 0.25f * kSpacing, 0.7f * kSpacing, kSpacing}) {
    FluidExportSettings s = settings();
    s.voxel_size = voxel;
    expect_every_particle_inside(block(10, 7, 5, openvdb::Vec3d(0.01, 0.02, 0.03)), s,
                                 "lattice block");
    expect_every_particle_inside(splash(7), s, "splash");
  }
  // A block that moved: jittered by up to a quarter spacing.
  FluidParticles p = block(16, 16, 16, openvdb::Vec3d(-0.3, 0.1, 0.2));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(-0.25f * kSpacing, 0.25f * kSpacing);
  for (std::size_t i = 0; i < p.size(); ++i)
    p.x[i] += jitter(rng), p.y[i] += jitter(rng), p.z[i] += jitter(rng);
  expect_every_particle_inside(p, settings(), "jittered block");
}

/// The surface's stages, from the internal header: the raw field (no smoothing) or the full one.
openvdb::FloatGrid::Ptr internal_surface(const FluidParticles& p, int smoothing_passes) {
  openvdb::initialize();
  seiche::exporting::SurfaceShape shape;
  shape.spacing = kSpacing, shape.voxel_size = kVoxel, shape.half_width = float(kHalfWidth);
  shape.smoothing_passes = smoothing_passes;
  return seiche::exporting::fluid_surface(p.x, p.y, p.z, p.vx, p.vy, p.vz, shape, false).surface;
}

// The fast raw field (binned, leaf-parallel, deep leaves skipped) against the field it stands
// for, evaluated directly over every particle in double precision at voxel centres.
TEST(Surface, RawFieldMatchesTheBruteForceField) {
  const FluidParticles p = concat(block(18, 18, 18, openvdb::Vec3d(0.50, 0.50, 0.50)), splash(11));
  const auto grid = internal_surface(p, 0);
  const double s = kSpacing, dx = kVoxel, h = 2.0 * s,
               rho = double(seiche::exporting::kParticleSphereRadius) * s;
  // c is normalised by the smallest kernel sum over a rest lattice's cell (spacing 1, h = 2).
  double lattice = std::numeric_limits<double>::max();
  for (double a = 0.0; a <= 0.5; a += 0.0625)
    for (double b = 0.0; b <= 0.5; b += 0.0625)
      for (double e = 0.0; e <= 0.5; e += 0.0625) {
        double sum = 0.0;
        for (int i = -3; i <= 3; ++i)
          for (int j = -3; j <= 3; ++j)
            for (int k = -3; k <= 3; ++k)
              sum += std::pow(
                  std::max(0.0,
                           1.0 - ((i - a) * (i - a) + (j - b) * (j - b) + (k - e) * (k - e)) / 4.0),
                  3);
        lattice = std::min(lattice, sum);
      }
  const auto brute_phi = [&](const openvdb::Vec3d& x) {
    double c = 0.0, nearest = std::numeric_limits<double>::max();
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double r2 = (x - openvdb::Vec3d(p.x[i], p.y[i], p.z[i])).lengthSqr(),
                   q = 1.0 - r2 / (h * h);
      nearest = std::min(nearest, r2);
      if (q > 0.0) c += q * q * q;
    }
    // The distance t h at which a flat face reads density c / lattice: 1/2 - G(t) / 2 G(1) = c.
    const auto G = [](double t) {
      return t - 4 * t * t * t / 3 + 6 * std::pow(t, 5) / 5 - 4 * std::pow(t, 7) / 7 +
             std::pow(t, 9) / 9;
    };
    double lo = -1.0, hi = 1.0;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (0.5 - G(mid) / (2 * G(1.0)) > c / lattice ? lo : hi) = mid;
    }
    double phi = 0.5 * (lo + hi) * h;
    if (nearest < h * h) phi = std::min(phi, std::sqrt(nearest) - rho);
    return std::clamp(phi, -kHalfWidth * dx, kHalfWidth * dx);
  };
  // Every 7th voxel of the particles' bounding box, expanded by the kernel radius.
  openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
  box.expand(2);
  std::size_t active = 0, inactive = 0, sign_errors = 0;
  double worst_active = 0.0, deep_max_phi = -1e9;
  std::size_t visited = 0;
  for (auto ijk = box.begin(); ijk; ++ijk, ++visited) {
    if (visited % 7 != 0) continue;
    const openvdb::Vec3d x = grid->indexToWorld(*ijk);
    const double exact = brute_phi(x);
    float value = 0.0f;
    const bool on = grid->tree().probeValue(*ijk, value);
    if (on) {
      ++active;
      worst_active = std::max(worst_active, std::abs(value - exact));
    } else {
      ++inactive;
      sign_errors += (value < 0) != (exact < 0);
      if (value < 0) deep_max_phi = std::max(deep_max_phi, exact);
    }
  }
  std::printf(
      "[ oracle ] %zu active voxels: max |fast - brute force| = %.2e voxels; %zu inactive, %zu "
      "sign "
      "errors; deepest inactive-inside voxel reads %.2f voxels\n",
      active, worst_active / dx, inactive, sign_errors, deep_max_phi / dx);
  EXPECT_GT(active, 1000u);
  EXPECT_LT(worst_active, 1e-3 * dx);
  EXPECT_EQ(sign_errors, 0u);
  // Voxels stored as "inside, beyond the band" must really lie deep: not in the band's outer half.
  EXPECT_LT(deep_max_phi, -0.5 * kHalfWidth * dx);
}

// The smoothing (leaf by leaf, with halos read from the neighbours) against two passes of the
// 3-voxel box filter applied to the whole raw field, shifted by the erosion, on a block not
// aligned with the leaves (so every halo crosses leaves). Voxels whose filter support reaches the
// raw field's inner clamp are left out: the shift is applied before that clamp.
TEST(Surface, SmoothingIsTwoBoxFilterPassesOfTheRawField) {
  const FluidParticles p = block(21, 17, 19, openvdb::Vec3d(0.0113, 0.0571, -0.0307));
  const auto raw = internal_surface(p, 0);
  const auto smooth = internal_surface(p, 2);
  const double e = double(seiche::exporting::kErosion) * kSpacing, w = kHalfWidth * kVoxel;
  openvdb::CoordBBox box = smooth->evalActiveVoxelBoundingBox();
  box.expand(3);
  const openvdb::Coord lo = box.min(), dim = box.dim();
  const auto at = [&](int i, int j, int k) { return (std::size_t(i) * dim.y() + j) * dim.z() + k; };
  std::vector<double> a(std::size_t(dim.x()) * dim.y() * dim.z()), b(a.size());
  std::vector<char> clamped(a.size());
  for (int i = 0; i < dim.x(); ++i)
    for (int j = 0; j < dim.y(); ++j)
      for (int k = 0; k < dim.z(); ++k) {
        const double v = raw->tree().getValue(lo.offsetBy(i, j, k));
        clamped[at(i, j, k)] = v <= -w + 1e-6;
        a[at(i, j, k)] = std::clamp(v + e, -w, w);
      }
  for (int pass = 0; pass < 2; ++pass)
    for (int axis = 0; axis < 3; ++axis) {
      b = a;
      for (int i = 1; i + 1 < dim.x(); ++i)
        for (int j = 1; j + 1 < dim.y(); ++j)
          for (int k = 1; k + 1 < dim.z(); ++k) {
            const int di = axis == 0, dj = axis == 1, dk = axis == 2;
            a[at(i, j, k)] =
                (b[at(i - di, j - dj, k - dk)] + b[at(i, j, k)] + b[at(i + di, j + dj, k + dk)]) /
                3.0;
          }
    }
  std::size_t compared = 0, lowered = 0;
  double worst = 0.0;
  for (int i = 2; i + 2 < dim.x(); ++i)
    for (int j = 2; j + 2 < dim.y(); ++j)
      for (int k = 2; k + 2 < dim.z(); ++k) {
        bool near_clamp = false;
        for (int di = -2; di <= 2; ++di)
          for (int dj = -2; dj <= 2; ++dj)
            for (int dk = -2; dk <= 2; ++dk)
              near_clamp = near_clamp || clamped[at(i + di, j + dj, k + dk)];
        if (near_clamp) continue;
        ++compared;
        // Beads (particles the smoothing left outside: here the block's corner particles) only
        // lower.
        const double d =
            smooth->tree().getValue(lo.offsetBy(i, j, k)) - std::clamp(a[at(i, j, k)], -w, w);
        if (d < -1e-4 * kVoxel)
          ++lowered;
        else
          worst = std::max(worst, std::abs(d));
      }
  std::printf(
      "[ smoothing ] %zu voxels: max |leaf-wise - whole-grid filter| = %.2e voxels, %zu lowered by "
      "beads\n",
      compared, worst / kVoxel, lowered);
  EXPECT_GT(compared, 20000u);
  EXPECT_LT(worst, 1e-4 * kVoxel);
  EXPECT_LT(lowered, compared / 100);
}

TEST(Surface, SameBytesForAnyThreadCount) {
  const FluidParticles p = concat(block(30, 20, 25, openvdb::Vec3d(0.0, 0.0, 0.0)), splash(5));
  FluidExportSettings s = settings(true, true, true, true);
  s.mesh = true;
  EncodedFluidFrame one, two;
  seiche::run_with_threads(1, [&] { one = seiche::encode_fluid_frame(p, s, {4, 0.25}); });
  seiche::run_with_threads(2, [&] { two = seiche::encode_fluid_frame(p, s, {4, 0.25}); });
  EXPECT_TRUE(one.vdb == two.vdb);
  EXPECT_TRUE(one.obj == two.obj);
}

// ---- The file ----------------------------------------------------------------------------------

TEST(FrameFile, GridsClassesTransformAndMetadata) {
  FluidExportSettings s = settings(true, true, true, true);
  s.scene_name = "dam_break";
  const FluidParticles p = block(10, 8, 8, openvdb::Vec3d(0.5, 0.25, 0.125));
  const Decoded d = decode(seiche::encode_fluid_frame(p, s, {7, 7.0 / 60.0}).vdb);
  ASSERT_EQ(d.grids.size(), 4u);
  EXPECT_EQ(d.grids[0]->getName(), "surface");
  EXPECT_EQ(d.grids[1]->getName(), "density");
  EXPECT_EQ(d.grids[2]->getName(), "v");
  EXPECT_EQ(d.grids[3]->getName(), "points");
  EXPECT_EQ(d.grids[0]->getGridClass(), openvdb::GRID_LEVEL_SET);
  EXPECT_EQ(d.grids[1]->getGridClass(), openvdb::GRID_FOG_VOLUME);
  EXPECT_TRUE(d.grids[0]->isType<openvdb::FloatGrid>());
  EXPECT_TRUE(d.grids[1]->isType<openvdb::FloatGrid>());
  EXPECT_TRUE(d.grids[2]->isType<openvdb::Vec3SGrid>());
  EXPECT_TRUE(d.grids[3]->isType<openvdb::points::PointDataGrid>());
  EXPECT_EQ(d.grids[2]->getVectorType(), openvdb::VEC_CONTRAVARIANT_RELATIVE);
  for (int g = 0; g < 3; ++g) {
    const openvdb::math::Transform& t = d.grids[g]->transform();
    EXPECT_TRUE(t.isLinear() && d.grids[g]->hasUniformVoxels());
    EXPECT_NEAR(d.grids[g]->voxelSize()[0], kVoxel, 1e-9);
    const openvdb::Vec3d w = t.indexToWorld(openvdb::Coord(3, -2, 5));
    EXPECT_NEAR((w - kVoxel * openvdb::Vec3d(3, -2, 5)).length(), 0.0, 1e-9);  // no offset
  }
  const auto surface = d.get<openvdb::FloatGrid>("surface");
  EXPECT_FLOAT_EQ(surface->background(), float(kHalfWidth) * kVoxel);
  const auto density = d.get<openvdb::FloatGrid>("density");
  const openvdb::Vec3d centre(0.5 + 5 * kSpacing, 0.25 + 4 * kSpacing, 0.125 + 4 * kSpacing);
  EXPECT_FLOAT_EQ(float(sample(*density, centre)), 1.0f);
  EXPECT_FLOAT_EQ(float(sample(*density, centre + openvdb::Vec3d(1.0, 0, 0))), 0.0f);
  EXPECT_NEAR(d.grids[3]->voxelSize()[0], 2.0 * kSpacing, 1e-9);
  EXPECT_EQ(d.metadata->metaValue<std::string>("seiche_scene"), "dam_break");
  EXPECT_EQ(d.metadata->metaValue<openvdb::Int32>("seiche_frame"), 7);
  EXPECT_DOUBLE_EQ(d.metadata->metaValue<double>("seiche_time"), 7.0 / 60.0);
  const std::string version = d.metadata->metaValue<std::string>("seiche_version");
  EXPECT_TRUE(std::regex_match(version, std::regex(R"(\d+\.\d+\.\d+)"))) << version;
  EXPECT_FLOAT_EQ(d.metadata->metaValue<float>("seiche_voxel_size"), kVoxel);
  EXPECT_FLOAT_EQ(d.metadata->metaValue<float>("seiche_spacing"), kSpacing);
  for (const auto& g : d.grids) EXPECT_EQ(g->getCreator(), "Seiche " + version);

  // Only what is asked.
  const Decoded only = decode(seiche::encode_fluid_frame(p, settings(false, true), {1, 0.0}).vdb);
  ASSERT_EQ(only.grids.size(), 1u);
  EXPECT_EQ(only.grids[0]->getName(), "density");
  FluidExportSettings coarse = settings();
  coarse.voxel_size = 0.8f * kSpacing;
  EXPECT_NEAR(surface_of(p, coarse)->voxelSize()[0], double(0.8f * kSpacing), 1e-9);
}

TEST(FrameFile, RewriteIsByteIdenticalAndReadsBack) {
  const FluidParticles p = concat(block(12, 9, 10, openvdb::Vec3d(0.0, 0.1, 0.2)), splash(2));
  FluidExportSettings s = settings(true, true, true, true);
  const std::string a = seiche::encode_fluid_frame(p, s, {12, 0.2}).vdb;
  const std::string b = seiche::encode_fluid_frame(p, s, {12, 0.2}).vdb;
  ASSERT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b);
  // The header's UUID (OpenVDB writes a random one) depends on the scene and the frame only.
  const std::string c = seiche::encode_fluid_frame(p, s, {13, 0.2}).vdb;
  EXPECT_NE(a.substr(21, 36), c.substr(21, 36));
  const Decoded d = decode(a);
  EXPECT_EQ(d.grids.size(), 4u);
  EXPECT_GT(d.get<openvdb::FloatGrid>("surface")->activeVoxelCount(), 1000u);
}

TEST(FrameFile, CompressionAndHalfFloatAreInTheFile) {
  const FluidParticles p = block(24, 24, 24, openvdb::Vec3d(0.0, 0.0, 0.0));
  std::map<std::string, std::string> bytes;
  std::map<std::string, std::uint32_t> flags;
  for (const char* c : {"blosc", "zip", "none"}) {
    FluidExportSettings s = settings(true, false, true, true);
    s.compression = c;
    bytes[c] = seiche::encode_fluid_frame(p, s, {1, 0.0}).vdb;
    flags[c] = decode(bytes[c]).last_grid_compression;  // of the points grid, written last
  }
  EXPECT_EQ(flags["blosc"],
            std::uint32_t(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK));
  EXPECT_EQ(flags["zip"],
            std::uint32_t(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK));
  EXPECT_EQ(flags["none"], std::uint32_t(openvdb::io::COMPRESS_NONE));
  std::printf("[ sizes ] blosc %zu, zip %zu, none %zu bytes\n", bytes["blosc"].size(),
              bytes["zip"].size(), bytes["none"].size());
  EXPECT_LT(bytes["blosc"].size(), 0.8 * bytes["none"].size());
  EXPECT_LT(bytes["zip"].size(), 0.8 * bytes["none"].size());

  FluidExportSettings full = settings(true, true, false, true), half = full;
  full.compression = half.compression = "none";
  half.half_float = true;
  const std::string full_bytes = seiche::encode_fluid_frame(p, full, {1, 0.0}).vdb;
  const std::string half_bytes = seiche::encode_fluid_frame(p, half, {1, 0.0}).vdb;
  std::printf("[ sizes ] float %zu, half %zu bytes\n", full_bytes.size(), half_bytes.size());
  EXPECT_LT(half_bytes.size(), 0.65 * full_bytes.size());
  const auto a = decode(full_bytes).get<openvdb::FloatGrid>("surface");
  const auto b = decode(half_bytes).get<openvdb::FloatGrid>("surface");
  double worst = 0.0;
  for (auto it = a->cbeginValueOn(); it; ++it)
    worst = std::max(worst, double(std::abs(*it - b->tree().getValue(it.getCoord()))));
  EXPECT_GT(worst, 0.0);                         // rounded ...
  EXPECT_LT(worst, 2e-3 * kHalfWidth * kVoxel);  // ... to 11 bits
}

// ---- Points and velocity -----------------------------------------------------------------------

TEST(Points, RoundTripPositionsVelocitiesAndIds) {
  FluidParticles p = concat(block(9, 7, 5, openvdb::Vec3d(-0.31, 1.7, 0.05)), splash(9));
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (std::size_t i = 0; i < p.size(); ++i) p.vx[i] = u(rng), p.vy[i] = u(rng), p.vz[i] = u(rng);
  for (const bool half : {false, true}) {
    FluidExportSettings s = settings(false, false, true);
    s.half_float = half;
    const auto grid = decode(seiche::encode_fluid_frame(p, s, {1, 0.0}).vdb)
                          .get<openvdb::points::PointDataGrid>("points");
    ASSERT_TRUE(grid);
    std::vector<int> seen(p.size(), 0);
    double worst_position = 0.0, worst_velocity = 0.0;
    for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
      const openvdb::points::AttributeHandle<openvdb::Vec3f> position(
          leaf->constAttributeArray("P"));
      const openvdb::points::AttributeHandle<openvdb::Vec3f> velocity(
          leaf->constAttributeArray("v"));
      const openvdb::points::AttributeHandle<std::int32_t> id(leaf->constAttributeArray("id"));
      for (auto index = leaf->beginIndexOn(); index; ++index) {
        const std::int32_t i = id.get(*index);
        ASSERT_TRUE(i >= 0 && std::size_t(i) < p.size());
        ++seen[std::size_t(i)];
        const openvdb::Vec3d world =
            grid->transform().indexToWorld(position.get(*index) + index.getCoord().asVec3d());
        worst_position =
            std::max(worst_position, (world - openvdb::Vec3d(p.x[i], p.y[i], p.z[i])).length());
        const openvdb::Vec3f v = velocity.get(*index);
        worst_velocity = std::max(worst_velocity,
                                  double((v - openvdb::Vec3f(p.vx[i], p.vy[i], p.vz[i])).length()));
      }
    }
    std::printf("[ points ] half %d: max position error %.2e m, max velocity error %.2e m/s\n",
                int(half), worst_position, worst_velocity);
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1),
              std::ptrdiff_t(p.size()));  // every id exactly once
    EXPECT_LT(worst_position, 1e-4);
    if (half)
      EXPECT_LT(worst_velocity, 3.0 * 3.0 / 1024.0);  // half floats: 11 significant bits
    else
      EXPECT_EQ(worst_velocity, 0.0);
  }
}

TEST(Velocity, UniformAndShearMotionOnTheSurfaceBand) {
  FluidParticles p = block(14, 10, 12, openvdb::Vec3d(0.0, 0.0, 0.0));
  for (std::size_t i = 0; i < p.size(); ++i) p.vx[i] = 1.0f, p.vy[i] = -2.0f, p.vz[i] = 0.5f;
  Decoded d =
      decode(seiche::encode_fluid_frame(p, settings(true, false, false, true), {1, 0.0}).vdb);
  auto v = d.get<openvdb::Vec3SGrid>("v");
  auto surface = d.get<openvdb::FloatGrid>("surface");
  ASSERT_TRUE(v && surface);
  // v is on the surface's band, wherever the kernel reaches: all of the band but its outer rim.
  std::size_t v_off_band = 0, band_without_v = 0;
  for (auto it = v->cbeginValueOn(); it; ++it)
    v_off_band += !surface->tree().isValueOn(it.getCoord());
  for (auto it = surface->cbeginValueOn(); it; ++it)
    band_without_v += *it < 1.5f * kVoxel && !v->tree().isValueOn(it.getCoord());
  EXPECT_GT(v->activeVoxelCount(), surface->activeVoxelCount() / 2);
  EXPECT_EQ(v_off_band, 0u);
  EXPECT_EQ(band_without_v, 0u);
  double worst = 0.0;
  for (auto it = v->cbeginValueOn(); it; ++it)
    worst = std::max(worst, double((*it - openvdb::Vec3s(1, -2, 0.5)).length()));
  EXPECT_LT(worst, 1e-5);
  // Shear v = (y / s, 0, 0) m/s: the kernel-weighted velocity of a voxel is that of its
  // neighbourhood, within a kernel radius (2 spacings) of its own y.
  for (std::size_t i = 0; i < p.size(); ++i)
    p.vx[i] = p.y[i] / kSpacing, p.vy[i] = 0.0f, p.vz[i] = 0.0f;
  d = decode(seiche::encode_fluid_frame(p, settings(true, false, false, true), {1, 0.0}).vdb);
  v = d.get<openvdb::Vec3SGrid>("v");
  worst = 0.0;
  for (auto it = v->cbeginValueOn(); it; ++it) {
    const double y = v->indexToWorld(it.getCoord())[1];
    const double clamped =
        std::clamp(y, 0.5 * kSpacing, 9.5 * kSpacing);  // particle rows span these y
    worst = std::max(worst, std::abs((*it)[0] - clamped / kSpacing));
  }
  EXPECT_LT(worst, 2.0);
}

// ---- The mesh ----------------------------------------------------------------------------------

struct ObjMesh {
  std::vector<openvdb::Vec3d> v, vn;
  std::vector<std::vector<int>> faces;  // 0-based vertex indices
};

ObjMesh parse_obj(const std::string& text) {
  ObjMesh m;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream l(line);
    std::string tag;
    l >> tag;
    if (tag == "v" || tag == "vn") {
      openvdb::Vec3d x;
      l >> x[0] >> x[1] >> x[2];
      (tag == "v" ? m.v : m.vn).push_back(x);
    } else if (tag == "f") {
      std::vector<int> f;
      std::string corner;
      while (l >> corner) {
        const int vi = std::stoi(corner.substr(0, corner.find('/')));
        const int ni = std::stoi(corner.substr(corner.rfind('/') + 1));
        EXPECT_EQ(vi, ni);
        f.push_back(vi - 1);
      }
      m.faces.push_back(f);
    }
  }
  return m;
}

TEST(Mesh, ClosedSurfaceOnTheZeroCrossingWithTheBlocksVolume) {
  const std::array<int, 3> n{16, 12, 10};
  const openvdb::Vec3d lo(0.05, 0.4, -0.2);
  FluidExportSettings s = settings(true);
  s.mesh = true;
  const EncodedFluidFrame frame =
      seiche::encode_fluid_frame(block(n[0], n[1], n[2], lo), s, {3, 0.05});
  const ObjMesh m = parse_obj(frame.obj);
  const auto surface = decode(frame.vdb).get<openvdb::FloatGrid>("surface");
  ASSERT_GT(m.faces.size(), 1000u);
  ASSERT_EQ(m.v.size(), m.vn.size());
  // Closed and manifold: every edge is used by exactly two faces, once in each direction.
  std::map<std::pair<int, int>, int> directed;
  for (const auto& f : m.faces)
    for (std::size_t k = 0; k < f.size(); ++k) ++directed[{f[k], f[(k + 1) % f.size()]}];
  int open_edges = 0;
  for (const auto& [edge, count] : directed)
    open_edges += count != 1 || directed.count({edge.second, edge.first}) != 1;
  EXPECT_EQ(open_edges, 0);
  // Vertices on the zero crossing; normals unit and outward.
  double worst_phi = 0.0;
  int inward = 0;
  const openvdb::Vec3d centre = lo + 0.5 * kSpacing * openvdb::Vec3d(n[0], n[1], n[2]);
  for (std::size_t i = 0; i < m.v.size(); ++i) {
    worst_phi = std::max(worst_phi, std::abs(sample(*surface, m.v[i])));
    EXPECT_NEAR(m.vn[i].length(), 1.0, 1e-3);
    inward += m.vn[i].dot(m.v[i] - centre) <= 0.0;
  }
  EXPECT_LT(worst_phi, 0.5 * kVoxel);
  EXPECT_EQ(inward, 0);
  // Volume by the divergence theorem: sum over triangles of det(a, b, c) / 6 (positive when the
  // faces wind counter-clockwise seen from outside).
  double volume = 0.0;
  for (const auto& f : m.faces)
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      volume += m.v[f[0]].dot(m.v[f[k]].cross(m.v[f[k + 1]])) / 6.0;
  const double exact = double(n[0]) * n[1] * n[2] * std::pow(double(kSpacing), 3);
  std::printf(
      "[ mesh ] %zu vertices, %zu faces, max |phi| at a vertex %.3f voxels, volume %.3f %% off\n",
      m.v.size(), m.faces.size(), worst_phi / kVoxel, 100.0 * (volume / exact - 1.0));
  EXPECT_NEAR(volume / exact, 1.0, 0.05);
}

// ---- The exporter ------------------------------------------------------------------------------

seiche::SceneDef scene_with_fluid() {
  seiche::SceneDef scene;
  scene.name = "pool";
  seiche::FluidDef fluid;
  fluid.spacing = kSpacing;
  fluid.box = {{0, 0, 0}, {0.2f, 0.2f, 0.2f}};
  scene.fluids.push_back(fluid);
  scene.output.vdb_points = true;
  scene.output.mesh = true;
  return scene;
}

/// A store as a simulation leaves it: cell order (here: shuffled), raw particles in between.
seiche::ParticleStore shuffled_store(const FluidParticles& fluid, int raw_particles) {
  const std::size_t n = fluid.size() + std::size_t(raw_particles);
  std::vector<std::size_t> slot(n);
  for (std::size_t i = 0; i < n; ++i) slot[i] = i;
  std::shuffle(slot.begin(), slot.end(), std::mt19937(4));
  seiche::ParticleStore store;
  store.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = slot[i];
    const bool is_fluid = i < fluid.size();
    store.x[k] = is_fluid ? fluid.x[i] : 5.0f, store.y[k] = is_fluid ? fluid.y[i] : 5.0f;
    store.z[k] = is_fluid ? fluid.z[i] : 5.0f;
    store.vx[k] = is_fluid ? fluid.vx[i] : 9.0f, store.vy[k] = is_fluid ? fluid.vy[i] : 9.0f;
    store.vz[k] = is_fluid ? fluid.vz[i] : 9.0f;
    store.w[k] = 1.0f;
    store.phase[k] =
        seiche::make_phase(is_fluid ? seiche::Material::Fluid : seiche::Material::Free);
    store.id[k] = std::int32_t(i);
  }
  return store;
}

std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = seiche::testing_support::temp_path("seiche_export_tests_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(Exporter, WritesTheFilesItListsFromTheStoreInIdOrder) {
  const seiche::SceneDef scene = scene_with_fluid();
  const auto exporter = seiche::make_vdb_exporter(scene);
  ASSERT_TRUE(exporter);
  EXPECT_EQ(exporter->name(), "vdb");
  const auto files = exporter->files(3);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0], std::filesystem::path("pool.0003.vdb"));
  EXPECT_EQ(files[1], std::filesystem::path("pool.0003.obj"));

  const FluidParticles fluid = block(10, 10, 10, openvdb::Vec3d(0.0, 0.0, 0.0));
  const seiche::ParticleStore store = shuffled_store(fluid, 50);
  const seiche::FluidParticles gathered = seiche::gather_fluid_particles(store);
  ASSERT_EQ(gathered.size(), fluid.size());
  EXPECT_TRUE(gathered.id == fluid.id && gathered.x == fluid.x && gathered.vz == fluid.vz);

  const auto dir = fresh_dir("exporter");
  const std::uint64_t bytes = exporter->write_frame({store, scene, 3, 0.05}, dir);
  std::uint64_t on_disk = 0;
  for (const auto& f : files) {
    ASSERT_TRUE(std::filesystem::exists(dir / f)) << f;
    on_disk += std::filesystem::file_size(dir / f);
  }
  EXPECT_EQ(bytes, on_disk);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir),
                          std::filesystem::directory_iterator()),
            2);
  std::ifstream in(dir / files[0], std::ios::binary);
  const std::string written((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  FluidExportSettings s = seiche::fluid_export_settings(scene);
  EXPECT_TRUE(written ==
              seiche::encode_fluid_frame(fluid, s, {3, 0.05}).vdb);  // the raw particles left out
  std::filesystem::remove_all(dir);
}

TEST(Exporter, NullWhenNothingIsAskedOrThereIsNoFluid) {
  seiche::SceneDef scene = scene_with_fluid();
  scene.output.vdb_surface = scene.output.vdb_density = scene.output.vdb_points =
      scene.output.vdb_velocity = false;
  scene.output.mesh = false;
  EXPECT_EQ(seiche::make_vdb_exporter(scene), nullptr);
  scene.output.mesh = true;
  EXPECT_NE(seiche::make_vdb_exporter(scene), nullptr);
  EXPECT_EQ(seiche::make_vdb_exporter(scene)->files(1).size(), 1u);  // the mesh only
  scene.fluids.clear();
  EXPECT_EQ(seiche::make_vdb_exporter(scene), nullptr);
}

TEST(Exporter, UnwritableTargetGivesAnIoErrorNamingTheFile) {
  const seiche::SceneDef scene = scene_with_fluid();
  const auto exporter = seiche::make_vdb_exporter(scene);
  const seiche::ParticleStore store = shuffled_store(block(4, 4, 4, openvdb::Vec3d(0.0)), 0);
  const auto dir = fresh_dir("unwritable");
  const auto not_a_dir = dir / "plain_file";
  std::ofstream(not_a_dir) << "x";
  try {
    exporter->write_frame({store, scene, 1, 0.0}, not_a_dir);
    FAIL() << "no IoError";
  } catch (const seiche::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("pool.0001.vdb"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(Exporter, BadVoxelSizeOrCompressionIsRejectedClearly) {
  seiche::SceneDef scene = scene_with_fluid();
  const auto expect_scene_error = [&](const char* path, const char* words) {
    try {
      (void)seiche::make_vdb_exporter(scene);
      ADD_FAILURE() << "no SceneError for " << path;
    } catch (const seiche::SceneError& e) {
      EXPECT_EQ(e.json_path(), path);
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  scene.output.voxel_size = 1.5f * kSpacing;
  expect_scene_error("output.voxel_size", "coarser than the fluid spacing");
  scene.output.voxel_size = 0.2f * kSpacing;
  expect_scene_error("output.voxel_size", "finer than a quarter");
  scene.output.voxel_size = -1.0f;
  expect_scene_error("output.voxel_size", ">= 0");
  scene.output.voxel_size = std::numeric_limits<float>::quiet_NaN();
  expect_scene_error("output.voxel_size", ">= 0");
  scene.output.voxel_size = 0.0f;
  scene.output.compression = "lz4";
  expect_scene_error("output.compression", "\"lz4\"");
  scene.output.compression = "zip";
  EXPECT_NE(seiche::make_vdb_exporter(scene), nullptr);

  FluidExportSettings s = settings();
  s.voxel_size = 2.0f * kSpacing;
  EXPECT_THROW(seiche::encode_fluid_frame(block(2, 2, 2, openvdb::Vec3d(0.0)), s, {1, 0.0}),
               std::invalid_argument);
  FluidParticles torn = block(2, 2, 2, openvdb::Vec3d(0.0));
  torn.id.pop_back();
  EXPECT_THROW(seiche::encode_fluid_frame(torn, settings(), {1, 0.0}), std::invalid_argument);
}

TEST(Exporter, NoFluidParticlesGivesValidEmptyFiles) {
  FluidExportSettings s = settings(true, true, true, true);
  s.mesh = true;
  const EncodedFluidFrame frame = seiche::encode_fluid_frame(FluidParticles{}, s, {1, 0.0});
  const Decoded d = decode(frame.vdb);
  ASSERT_EQ(d.grids.size(), 4u);
  EXPECT_EQ(d.grids[0]->activeVoxelCount(), 0u);
  EXPECT_EQ(parse_obj(frame.obj).faces.size(), 0u);
}

}  // namespace
