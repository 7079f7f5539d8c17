// Kernel layer: each kernel on a handful of particles, against hand math, physics or its scalar
// reference. No scene, no store: raw arrays, as the kernels see them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include <tbb/global_control.h>

#include "seiche/kernels/blocked_reduce.hpp"
#include "seiche/kernels/collisions.hpp"
#include "seiche/kernels/distance_constraint.hpp"
#include "seiche/kernels/integrate.hpp"
#include "seiche/kernels/pbf_density.hpp"
#include "seiche/kernels/pbf_walls.hpp"
#include "seiche/kernels/sph_kernels.hpp"
#include "seiche/kernels/vorticity_confinement.hpp"
#include "seiche/kernels/xsph_viscosity.hpp"

using namespace seiche;
using namespace seiche::kernels;

namespace {

// SoA particles for kernel tests.
struct Particles {
  std::vector<float> x, y, z, px, py, pz, vx, vy, vz, w;
  std::vector<float> radius;  // collision radii
  explicit Particles(std::size_t n, float r = 0.0f)
      : x(n), y(n), z(n), px(n), py(n), pz(n), vx(n), vy(n), vz(n), w(n, 1.0f), radius(n, r) {}
  void set(std::size_t i, float a, float b, float c) {
    x[i] = px[i] = a;
    y[i] = py[i] = b;
    z[i] = pz[i] = c;
  }
  ParticleView view() {
    return {x.size(), x.data(), y.data(), z.data(), px.data(), py.data(), pz.data(),
            vx.data(), vy.data(), vz.data(), w.data(), radius.data()};
  }
};

// All-pairs CSR neighbor list (self excluded): the kernels' input, built without the grid.
struct BruteNeighbors {
  std::vector<std::uint32_t> offsets{0}, indices;
  BruteNeighbors(const std::vector<Float4>& p, float radius) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      for (std::size_t j = 0; j < p.size(); ++j) {
        const float dx = p[i].x - p[j].x, dy = p[i].y - p[j].y, dz = p[i].z - p[j].z;
        if (i != j && dx * dx + dy * dy + dz * dz < radius * radius) indices.push_back(std::uint32_t(j));
      }
      offsets.push_back(std::uint32_t(indices.size()));
    }
  }
  NeighborSpan span() const { return {offsets.data(), indices.data()}; }
};

std::vector<Float4> lattice(int n, float spacing, float jitter, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-jitter, jitter);
  std::vector<Float4> p;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        p.push_back({(i + 0.5f) * spacing + u(rng), (j + 0.5f) * spacing + u(rng),
                     (k + 0.5f) * spacing + u(rng), 0.0f});
  return p;
}

PbfParams fluid_params(float spacing) {
  PbfParams prm;
  prm.h = 2.0f * spacing;
  prm.rest_density = 1000.0f;
  prm.mass = float(prm.rest_density / lattice_kernel_sum(spacing, prm.h));
  prm.epsilon = float(0.01 * lattice_lambda_denominator(spacing, prm.h));
  prm.lambda_scale = float(1.0 / lattice_lambda_denominator(spacing, prm.h));
  prm.tensile_k = 0.1f;
  prm.tensile_rest_distance = spacing;
  return prm;
}

}  // namespace

// ---- SPH kernels ------------------------------------------------------------------------------

TEST(SphKernel, Poly6IntegratesToOne) {
  const SphKernel k(0.1f);
  // Integral over the ball: sum of W(r) 4 pi r^2 dr.
  double sum = 0.0;
  const int steps = 20000;
  for (int s = 0; s < steps; ++s) {
    const double r = (s + 0.5) * 0.1 / steps;
    sum += k.poly6(float(r * r)) * 4.0 * M_PI * r * r * (0.1 / steps);
  }
  EXPECT_NEAR(sum, 1.0, 1e-4);
}

TEST(SphKernel, SpikyGradientMatchesFiniteDifferenceAndVanishesAtOrigin) {
  const SphKernel k(0.1f);
  auto spiky = [](double r) { return 15.0 / (M_PI * std::pow(0.1, 6)) * std::pow(0.1 - r, 3); };
  for (double r : {0.01, 0.05, 0.09}) {
    const double fd = (spiky(r + 1e-6) - spiky(r - 1e-6)) / 2e-6;
    EXPECT_NEAR(k.spiky_grad_over_r(float(r * r)) * r, fd, 1e-3 * std::abs(fd));
  }
  EXPECT_EQ(k.spiky_grad_over_r(0.0f), 0.0f);
  EXPECT_EQ(k.spiky_grad_over_r(0.011f), 0.0f);  // r > h
}

// ---- Distance constraint ----------------------------------------------------------------------

TEST(DistanceConstraint, SeedWorkedExample) {
  // m1 = 10, m2 = 2, p1 = (5,3,2), p2 = (1,5,6), d = 3  ->  (14/3, 19/6, 7/3), (8/3, 25/6, 13/3).
  Particles p(2);
  p.set(0, 5, 3, 2);
  p.set(1, 1, 5, 6);
  p.w = {0.1f, 0.5f};
  DistanceConstraints c;
  const std::uint32_t i[] = {0}, j[] = {1};
  const float rest[] = {3.0f}, compliance[] = {0.0f};
  color_distance_constraints(i, j, rest, compliance, 2, c);
  solve_distance_constraints(p.view(), c, 1.0f / 60.0f);
  EXPECT_NEAR(p.px[0], 14.0 / 3, 1e-5);
  EXPECT_NEAR(p.py[0], 19.0 / 6, 1e-5);
  EXPECT_NEAR(p.pz[0], 7.0 / 3, 1e-5);
  EXPECT_NEAR(p.px[1], 8.0 / 3, 1e-5);
  EXPECT_NEAR(p.py[1], 25.0 / 6, 1e-5);
  EXPECT_NEAR(p.pz[1], 13.0 / 3, 1e-5);
}

TEST(DistanceConstraint, CoincidentParticlesStayFinite) {
  Particles p(2);
  p.set(0, 1, 1, 1);
  p.set(1, 1, 1, 1);
  DistanceConstraints c;
  const std::uint32_t i[] = {0}, j[] = {1};
  const float rest[] = {0.5f}, compliance[] = {0.0f};
  color_distance_constraints(i, j, rest, compliance, 2, c);
  solve_distance_constraints(p.view(), c, 0.01f);
  for (float v : {p.px[0], p.py[0], p.pz[0], p.px[1], p.py[1], p.pz[1]}) EXPECT_TRUE(std::isfinite(v));
}

// The strain of a constraint at the particles' positions: |l - d| / d, and |l - d| in metres for
// d = 0; the error metric is its mean and max.
TEST(DistanceConstraint, EdgeStrainIsTheRelativeLengthError) {
  Particles p(3);
  p.set(0, 0, 0, 0);
  p.set(1, 3, 4, 0);  // |0 - 1| = 5
  p.set(2, 3, 4, 12);  // |1 - 2| = 12
  EXPECT_DOUBLE_EQ(edge_strain(p.view(), 0, 1, 4.0f), 0.25);
  EXPECT_DOUBLE_EQ(edge_strain(p.view(), 1, 0, 10.0f), 0.5);  // compressed: |5 - 10| / 10
  EXPECT_DOUBLE_EQ(edge_strain(p.view(), 0, 1, 5.0f), 0.0);
  EXPECT_DOUBLE_EQ(edge_strain(p.view(), 0, 1, 0.0f), 5.0);  // zero rest length: metres
  DistanceConstraints c;
  const std::uint32_t i[] = {0, 1}, j[] = {1, 2};
  const float rest[] = {4.0f, 16.0f}, compliance[] = {0.0f, 0.0f};
  color_distance_constraints(i, j, rest, compliance, 3, c);
  const DistanceError e = distance_constraint_error(p.view(), c);
  EXPECT_DOUBLE_EQ(e.mean, 0.25);  // (0.25 + 0.25) / 2
  EXPECT_DOUBLE_EQ(e.max, 0.25);
}

TEST(DistanceConstraint, ColoringSeparatesSharedParticles) {
  // A random graph: no two constraints of one color may share a particle, every input appears once.
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint32_t> pick(0, 199);
  std::vector<std::uint32_t> i, j;
  while (i.size() < 1000) {
    const std::uint32_t a = pick(rng), b = pick(rng);
    if (a != b) i.push_back(a), j.push_back(b);
  }
  std::vector<float> rest(i.size(), 1.0f), compliance(i.size(), 0.0f);
  DistanceConstraints c;
  const auto source = color_distance_constraints(i, j, rest, compliance, 200, c);
  std::vector<std::uint32_t> sorted_source(source);
  std::sort(sorted_source.begin(), sorted_source.end());
  for (std::size_t k = 0; k < sorted_source.size(); ++k) ASSERT_EQ(sorted_source[k], k);
  for (std::size_t col = 0; col + 1 < c.color_start.size(); ++col) {
    std::vector<int> seen(200, 0);
    for (std::uint32_t k = c.color_start[col]; k < c.color_start[col + 1]; ++k) {
      EXPECT_EQ(seen[c.i[k]]++, 0);
      EXPECT_EQ(seen[c.j[k]]++, 0);
    }
  }
  // A chain needs exactly two colors.
  std::vector<std::uint32_t> ci, cj;
  for (std::uint32_t k = 0; k < 9; ++k) ci.push_back(k), cj.push_back(k + 1);
  std::vector<float> r9(9, 1.0f), c9(9, 0.0f);
  color_distance_constraints(ci, cj, r9, c9, 10, c);
  EXPECT_EQ(c.color_start.size(), 3u);
}

TEST(DistanceConstraint, ComplianceGivesPhysicalStiffness) {
  // Static XPBD solve of one constraint against a pinned particle, pulled by a constant force f:
  // the equilibrium stretch is C = f * compliance, whatever the time step.
  for (float dt : {0.01f, 0.001f}) {
    Particles p(2);
    p.set(0, 0, 0, 0);
    p.set(1, 1, 0, 0);
    p.w = {0.0f, 1.0f};  // m = 1 kg
    const float compliance = 1e-3f, f = 5.0f;
    DistanceConstraints c;
    const std::uint32_t i[] = {0}, j[] = {1};
    const float rest[] = {1.0f}, comp[] = {compliance};
    color_distance_constraints(i, j, rest, comp, 2, c);
    // Quasi-static: steps of predict (with force) + iterations + zero velocity; with the velocity
    // zeroed, the stretch relaxes toward equilibrium by a factor 1 - dt^2 k / m per step
    // (k = 1 / compliance), so 20000 steps converge at both time steps.
    for (int step = 0; step < 20000; ++step) {
      p.vx[1] = p.vy[1] = p.vz[1] = 0.0f;
      const float g[3] = {f, 0, 0};  // a = f / m
      predict_positions(p.view(), dt, g);
      std::fill(c.lambda.begin(), c.lambda.end(), 0.0f);
      for (int it = 0; it < 20; ++it) solve_distance_constraints(p.view(), c, dt);
      update_velocities(p.view(), dt);
    }
    EXPECT_NEAR(p.x[1] - 1.0f, f * compliance, 0.02 * f * compliance) << "dt " << dt;
  }
}

// ---- Integration --------------------------------------------------------------------------------

TEST(Integrate, GravityMovesFreeParticlesOnly) {
  Particles p(2);
  p.set(0, 0, 1, 0);
  p.set(1, 0, 1, 0);
  p.w = {1.0f, 0.0f};
  const float g[3] = {0, -10, 0};
  predict_positions(p.view(), 0.1f, g);
  update_velocities(p.view(), 0.1f);
  EXPECT_NEAR(p.vy[0], -1.0f, 1e-6);
  EXPECT_NEAR(p.y[0], 1.0f - 0.1f, 1e-6);  // symplectic Euler: x += dt (v + dt g)
  EXPECT_EQ(p.vy[1], 0.0f);
  EXPECT_EQ(p.y[1], 1.0f);
}

// The integration passes are written lane = particle: every particle must get the bits of the
// scalar formulas (integrate.hpp), with pinned particles, negative zeros and a count that leaves
// a partial last batch and cuts the parallel loop into several tasks.
TEST(Integrate, PassesMatchTheScalarFormulasBitForBit) {
  const std::size_t n = 20003;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  Particles p(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.set(i, u(rng), u(rng), u(rng));
    p.vx[i] = u(rng), p.vy[i] = u(rng), p.vz[i] = i % 7 == 0 ? -0.0f : u(rng);
    p.w[i] = i % 5 == 0 ? 0.0f : 1.0f + u(rng) * u(rng);
  }
  const float dt = 1.0f / 300.0f, g[3] = {0.5f, -9.81f, 0.0f}, damping = 0.97f;
  Particles expected = p;
  for (std::size_t i = 0; i < n; ++i) {
    const float free = expected.w[i] > 0.0f ? 1.0f : 0.0f;
    expected.vx[i] += free * (dt * g[0]), expected.vy[i] += free * (dt * g[1]);
    expected.vz[i] += free * (dt * g[2]);
    expected.px[i] = expected.x[i] + dt * expected.vx[i] + u(rng) * 1e-3f;  // + a "solve"
    expected.py[i] = expected.y[i] + dt * expected.vy[i];
    expected.pz[i] = expected.z[i] + dt * expected.vz[i];
  }
  predict_positions(p.view(), dt, g);
  auto same = [&](const std::vector<float>& a, const std::vector<float>& b) {
    return std::memcmp(a.data(), b.data(), n * sizeof(float)) == 0;
  };
  EXPECT_TRUE(same(p.vx, expected.vx) && same(p.vy, expected.vy) && same(p.vz, expected.vz));
  EXPECT_TRUE(same(p.py, expected.py) && same(p.pz, expected.pz));
  p.px = expected.px;
  for (std::size_t i = 0; i < n; ++i) {
    const float inv_dt = 1.0f / dt;
    expected.vx[i] = (expected.px[i] - expected.x[i]) * inv_dt;
    expected.vy[i] = (expected.py[i] - expected.y[i]) * inv_dt;
    expected.vz[i] = (expected.pz[i] - expected.z[i]) * inv_dt;
    expected.x[i] = expected.px[i], expected.y[i] = expected.py[i], expected.z[i] = expected.pz[i];
    if (expected.w[i] > 0.0f) expected.vx[i] *= damping, expected.vy[i] *= damping, expected.vz[i] *= damping;
  }
  update_velocities(p.view(), dt);
  damp_velocities(p.view(), damping);
  EXPECT_TRUE(same(p.x, expected.x) && same(p.y, expected.y) && same(p.z, expected.z));
  EXPECT_TRUE(same(p.vx, expected.vx) && same(p.vy, expected.vy) && same(p.vz, expected.vz));
}

// ---- Position Based Fluids ----------------------------------------------------------------------

TEST(Pbf, RestLatticeIsAtRestDensity) {
  const float s = 0.1f;
  std::vector<Float4> pos = lattice(7, s, 0.0f);
  const PbfParams prm = fluid_params(s);
  BruteNeighbors nb(pos, prm.h);
  std::vector<float> rho(pos.size()), lambda(pos.size());
  pbf_density_lambda(pos.data(), nb.span(), pos.size(), prm, rho.data(), lambda.data());
  const std::size_t center = 3 * 49 + 3 * 7 + 3;  // a particle with a full neighborhood
  EXPECT_NEAR(rho[center], 1000.0f, 1e-2f);
  EXPECT_NEAR(lambda[center], 0.0f, 1e-6f);
  // Surface particles have fewer neighbors: lower density, no pull (unilateral constraint).
  EXPECT_LT(rho[0], 1000.0f);
  EXPECT_EQ(lambda[0], 0.0f);
}

TEST(Pbf, WallsMakeParticlesAtAWallReadRestDensity) {
  // A lattice whose bottom layer sits half a spacing above a wall: without the wall's share the
  // bottom layer reads about 19 % light; with it, within a few percent of rest density (the
  // continuous half-space lends slightly more than the missing lattice layer).
  const float s = 0.1f;
  std::vector<Float4> pos = lattice(9, s, 0.0f);
  PbfParams prm = fluid_params(s);
  BruteNeighbors nb(pos, prm.h);
  const std::size_t n = pos.size();
  const std::size_t bottom_center = 4 * 81 + 0 * 9 + 4, layer2_center = 4 * 81 + 1 * 9 + 4;
  std::vector<float> rho(n), lambda(n);
  pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda.data());
  EXPECT_LT(rho[bottom_center], 0.85f * prm.rest_density);
  prm.walls = true;
  prm.wall_min[0] = prm.wall_min[2] = -10.0f, prm.wall_min[1] = 0.0f;
  prm.wall_max[0] = prm.wall_max[1] = prm.wall_max[2] = 10.0f;
  pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda.data());
  EXPECT_NEAR(rho[bottom_center], prm.rest_density, 0.03f * prm.rest_density);  // continuous share
  EXPECT_NEAR(rho[layer2_center], prm.rest_density, 0.005f * prm.rest_density);
  // Scaled to the lattice's own missing share, the wall layer reads rest density.
  prm.wall_scale = float(lattice_wall_share(s, prm.h) / wall_density_fraction(0.5f * s, prm.h));
  pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda.data());
  EXPECT_NEAR(rho[bottom_center], prm.rest_density, 0.001f * prm.rest_density);
  // In a corner of three walls the shares combine without counting the overlap twice: within
  // a few percent of rest density (a plain sum of the three reads about 10 % heavy).
  prm.wall_min[0] = prm.wall_min[1] = prm.wall_min[2] = 0.0f;
  pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda.data());
  EXPECT_NEAR(rho[0], prm.rest_density, 0.03f * prm.rest_density);
  prm.wall_min[0] = prm.wall_min[2] = -10.0f;
  // Compressed toward the wall: Jacobi iterations lower the largest compression, wall layer
  // included (the wall takes part in the constraint; it does not only add density), and keep
  // the wall layer off the wall plane. (Jacobi is not monotone: the first iteration may
  // overshoot near the wall, so the test looks at the result of six.)
  for (auto& p : pos) p.y *= 0.9f;
  prm.epsilon = float(0.3 * lattice_lambda_denominator(s, prm.h));  // the default relaxation
  std::vector<float> px(n), py(n), pz(n);
  std::vector<float> errors;
  for (int it = 0; it < 6; ++it) {
    pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda.data());
    errors.push_back(*std::max_element(rho.begin(), rho.end()) / prm.rest_density - 1.0f);
    for (std::size_t i = 0; i < n; ++i) pos[i].w = lambda[i], px[i] = pos[i].x, py[i] = pos[i].y, pz[i] = pos[i].z;
    pbf_apply_correction(pos.data(), nb.span(), n, prm, px.data(), py.data(), pz.data());
    for (std::size_t i = 0; i < n; ++i) pos[i] = {px[i], py[i], pz[i], 0.0f};
    EXPECT_GT(py[bottom_center], prm.wall_min[1]);
  }
  EXPECT_GT(errors.front(), 0.05f);
  EXPECT_LT(errors.back(), 0.5f * errors.front());
}

// Runs both PBF passes vectorized and as the scalar reference on the same input (corrections
// added to positions that start at `start`), expects them to agree to 1e-4 of the largest value
// and everything to stay finite; returns the vectorized lambdas and corrected x, y, z.
struct PbfPassResult {
  std::vector<float> lambda, px, py, pz;
};
PbfPassResult expect_passes_match_reference(std::vector<Float4>& pos, const PbfParams& prm,
                                            const BruteNeighbors& nb, float start) {
  const std::size_t n = pos.size();
  std::vector<float> rho(n), lambda(n), rho_ref(n), lambda_ref(n);
  pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda.data());
  pbf_density_lambda_reference(pos.data(), nb.span(), n, prm, rho_ref.data(), lambda_ref.data());
  double max_lambda = 0.0;
  for (std::size_t i = 0; i < n; ++i) max_lambda = std::max(max_lambda, double(std::abs(lambda_ref[i])));
  EXPECT_GT(max_lambda, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_NEAR(rho[i], rho_ref[i], 1e-4f * rho_ref[i]) << i;
    EXPECT_NEAR(lambda[i], lambda_ref[i], 1e-4 * max_lambda) << i;
    pos[i].w = lambda_ref[i];
  }
  std::vector<float> px(n, start), py(n, start), pz(n, start), rx(n, start), ry(n, start), rz(n, start);
  pbf_apply_correction(pos.data(), nb.span(), n, prm, px.data(), py.data(), pz.data());
  pbf_apply_correction_reference(pos.data(), nb.span(), n, prm, rx.data(), ry.data(), rz.data());
  double max_dp = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    max_dp = std::max({max_dp, double(std::abs(rx[i] - start)), double(std::abs(ry[i] - start))});
  EXPECT_GT(max_dp, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_NEAR(px[i], rx[i], 1e-4 * max_dp) << i;
    EXPECT_NEAR(py[i], ry[i], 1e-4 * max_dp) << i;
    EXPECT_NEAR(pz[i], rz[i], 1e-4 * max_dp) << i;
    EXPECT_TRUE(std::isfinite(px[i]) && std::isfinite(py[i]) && std::isfinite(pz[i])) << i;
  }
  return {lambda, px, py, pz};
}

TEST(Pbf, VectorizedPassesMatchScalarReference) {
  const float s = 0.1f;
  std::vector<Float4> pos = lattice(9, 0.85f * s, 0.2f * s, 3);  // compressed and jittered
  // Two particles almost on top of each other: the coincident guard must agree too.
  pos[10] = pos[11];
  pos[10].x += 1e-7f;
  PbfParams prm = fluid_params(s);
  // Walls on three sides of the block (the others far away): the wall terms must agree too.
  prm.walls = true;
  for (int a = 0; a < 3; ++a) prm.wall_min[a] = 0.0f, prm.wall_max[a] = 10.0f;
  BruteNeighbors nb(pos, prm.h);
  expect_passes_match_reference(pos, prm, nb, 0.0f);
}

TEST(Pbf, RaggedAndEmptyNeighborListsMatchScalarReference) {
  // Lane = particle batches: lists of very different lengths in one batch, particles without
  // neighbors (first, middle and last), and a particle count that is not a multiple of the
  // batch width.
  const float s = 0.1f;
  std::vector<Float4> pos = lattice(5, 0.8f * s, 0.15f * s, 7);
  pos.insert(pos.begin(), Float4{-10.0f, -10.0f, -10.0f, 0.0f});
  pos.insert(pos.begin() + 60, Float4{10.0f, 10.0f, 10.0f, 0.0f});
  pos.push_back({10.0f, -10.0f, 10.0f, 0.0f});
  pos.push_back({-10.0f, 10.0f, -10.0f, 0.0f});  // n = 129
  const PbfParams prm = fluid_params(s);
  BruteNeighbors nb(pos, prm.h);
  const std::size_t n = pos.size();
  ASSERT_NE(n % 8, 0u);
  const PbfPassResult r = expect_passes_match_reference(pos, prm, nb, 1.0f);
  for (std::size_t i : {std::size_t(0), std::size_t(60), n - 1}) {
    EXPECT_EQ(r.lambda[i], 0.0f);  // no neighbors: no constraint, no motion
    EXPECT_EQ(r.px[i], 1.0f);
  }
}

// A boundary (rigid bodies' boundary particles, per particle (g_b, rho_b)) joins the density and
// the denominator's gradient in both passes alike; a particle with no fluid neighbor that the
// boundary compresses gets a lambda from the boundary alone, -C / (|g_b|^2 + eps).
TEST(Pbf, BoundaryDensityJoinsTheConstraintAsTheReferenceHasIt) {
  const float s = 0.1f;
  std::vector<Float4> pos = lattice(5, s, 0.1f * s, 11);  // at rest: lambda only from the boundary
  pos.push_back({10.0f, 10.0f, 10.0f, 0.0f});             // alone
  PbfParams prm = fluid_params(s);
  prm.epsilon = float(0.3 * lattice_lambda_denominator(s, prm.h));
  const std::size_t n = pos.size();
  std::vector<Float4> boundary(n);
  for (std::size_t i = 0; i < n; ++i)
    boundary[i] = {0.5f * float(i % 3), -1.0f, 0.25f, i % 2 ? 1.5f * prm.rest_density : 0.0f};
  prm.boundary = boundary.data();
  BruteNeighbors nb(pos, prm.h);
  expect_passes_match_reference(pos, prm, nb, 0.0f);
  std::vector<float> rho(n), lambda(n);
  pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda.data());
  const std::size_t alone = n - 1;  // odd: rho_b = 1.5 rho0 on top of m W(0)
  ASSERT_EQ(alone % 2, 1u);
  const double rho_alone = prm.mass * SphKernel(prm.h).poly6(0.0f) + 1.5 * prm.rest_density;
  EXPECT_NEAR(rho[alone], rho_alone, 1e-4 * rho_alone);
  const double g2 = 0.25 * double((alone % 3) * (alone % 3)) + 1.0 + 0.0625;
  const double c = std::max(rho_alone / prm.rest_density - 1.0, 0.0);
  ASSERT_GT(c, 0.5);
  EXPECT_NEAR(lambda[alone], -c / (g2 + prm.epsilon), 1e-4 * c / (g2 + prm.epsilon));
  prm.boundary = nullptr;  // without: the lattice at rest has no lambda anywhere
  std::vector<float> lambda_free(n);
  pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda_free.data());
  EXPECT_LT(lambda[1], lambda_free[1]);
}

TEST(Pbf, ArtificialPressurePushesOnlyPairsCloserThanTheRestSpacing) {
  // Two particles without density error (lambda 0): only s_corr moves them. At and beyond the
  // rest spacing it is exactly 0; closer, it pushes them apart, symmetrically; without a rest
  // distance (the paper's term) it pushes at the rest spacing too.
  const float s = 0.1f;
  auto push = [&](float r, float rest_distance) {
    PbfParams prm = fluid_params(s);
    prm.tensile_rest_distance = rest_distance;
    std::vector<Float4> pos = {{0.0f, 0.0f, 0.0f, 0.0f}, {r, 0.0f, 0.0f, 0.0f}};
    const BruteNeighbors nb(pos, prm.h);
    std::vector<float> px = {0.0f, r}, py(2, 0.0f), pz(2, 0.0f), rx = px, ry = py, rz = pz;
    pbf_apply_correction(pos.data(), nb.span(), 2, prm, px.data(), py.data(), pz.data());
    pbf_apply_correction_reference(pos.data(), nb.span(), 2, prm, rx.data(), ry.data(), rz.data());
    EXPECT_NEAR(px[0], rx[0], 1e-4 * std::abs(rx[0]) + 1e-12) << r;
    EXPECT_NEAR(px[0], -(px[1] - r), 1e-7f) << r;  // equal and opposite (up to rounding r + dp)
    EXPECT_EQ(py[0], 0.0f);
    return -px[0];  // how far particle 0 moved away from particle 1
  };
  EXPECT_EQ(push(s, s), 0.0f);
  EXPECT_EQ(push(1.3f * s, s), 0.0f);
  EXPECT_GT(push(0.9f * s, s), 0.0f);
  EXPECT_GT(push(0.5f * s, s), push(0.9f * s, s));
  EXPECT_GT(push(s, 0.0f), 0.0f);  // the unshifted term pushes at the rest spacing
  // At r = dq h the shifted term, rescaled, is the paper's k: the same push as the unshifted one.
  const float dq_h = fluid_params(s).tensile_dq * fluid_params(s).h;
  EXPECT_NEAR(push(dq_h, s), push(dq_h, 0.0f), 1e-5 * push(dq_h, 0.0f));
}

TEST(Pbf, JacobiIterationsReduceCompression) {
  // A block compressed to 90% spacing: each iteration must lower the max density error, and
  // the corrections conserve linear momentum (equal masses, antisymmetric pair terms).
  const float s = 0.1f;
  std::vector<Float4> pos = lattice(8, 0.9f * s, 0.0f);
  PbfParams prm = fluid_params(s);
  prm.tensile_k = 0.0f;
  const std::size_t n = pos.size();
  std::vector<float> rho(n), lambda(n), px(n), py(n), pz(n);
  double previous = 1e30;
  for (int it = 0; it < 6; ++it) {
    BruteNeighbors nb(pos, prm.h);
    pbf_density_lambda(pos.data(), nb.span(), n, prm, rho.data(), lambda.data());
    const double max_error = *std::max_element(rho.begin(), rho.end()) / prm.rest_density - 1.0;
    EXPECT_LT(max_error, previous) << "iteration " << it;
    previous = max_error;
    double sum_before[3] = {0, 0, 0}, sum_after[3] = {0, 0, 0};
    for (std::size_t i = 0; i < n; ++i) {
      pos[i].w = lambda[i];
      px[i] = pos[i].x, py[i] = pos[i].y, pz[i] = pos[i].z;
      sum_before[0] += px[i], sum_before[1] += py[i], sum_before[2] += pz[i];
    }
    pbf_apply_correction(pos.data(), nb.span(), n, prm, px.data(), py.data(), pz.data());
    for (std::size_t i = 0; i < n; ++i) {
      pos[i] = {px[i], py[i], pz[i], 0.0f};
      sum_after[0] += px[i], sum_after[1] += py[i], sum_after[2] += pz[i];
    }
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(sum_after[a], sum_before[a], 1e-6 * n);
  }
  EXPECT_LT(previous, 0.1);  // 6 iterations take out most of the 37 % initial compression
}

TEST(Pbf, ThreadCountDoesNotChangeResults) {
  const float s = 0.1f;
  std::vector<Float4> pos = lattice(12, 0.9f * s, 0.1f * s, 5);
  const PbfParams prm = fluid_params(s);
  BruteNeighbors nb(pos, prm.h);
  const std::size_t n = pos.size();
  auto solve = [&](int threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
    std::vector<float> rho(n), lambda(n), px(n, 0.0f), py(n, 0.0f), pz(n, 0.0f);
    std::vector<Float4> p = pos;
    pbf_density_lambda(p.data(), nb.span(), n, prm, rho.data(), lambda.data());
    for (std::size_t i = 0; i < n; ++i) p[i].w = lambda[i];
    pbf_apply_correction(p.data(), nb.span(), n, prm, px.data(), py.data(), pz.data());
    px.insert(px.end(), py.begin(), py.end());
    px.insert(px.end(), pz.begin(), pz.end());
    return px;
  };
  EXPECT_EQ(solve(1), solve(2));
}

// ---- Velocity passes ------------------------------------------------------------------------------

TEST(XsphViscosity, KeepsUniformFlowAndConservesMomentum) {
  const float s = 0.1f, h = 2 * s;
  std::vector<Float4> pos = lattice(6, s, 0.0f);
  const std::size_t n = pos.size();
  BruteNeighbors nb(pos, h);
  std::mt19937 rng(11);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<Float4> vel(n);
  const float volume = s * s * s;
  for (auto& v : vel) v = {g(rng), g(rng), g(rng), volume};
  std::vector<float> vx(n), vy(n), vz(n);
  xsph_viscosity(pos.data(), vel.data(), nb.span(), n, h, 0.5f, vx.data(), vy.data(), vz.data());
  double before[3] = {0, 0, 0}, after[3] = {0, 0, 0}, var_before = 0, var_after = 0;
  for (std::size_t i = 0; i < n; ++i) {
    before[0] += vel[i].x, before[1] += vel[i].y, before[2] += vel[i].z;
    after[0] += vx[i], after[1] += vy[i], after[2] += vz[i];
  }
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(after[a], before[a], 1e-4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    var_before += vel[i].x * vel[i].x + vel[i].y * vel[i].y + vel[i].z * vel[i].z;
    var_after += vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
  }
  EXPECT_LT(var_after, 0.9 * var_before);  // noise is smoothed out
  for (auto& v : vel) v = {1.0f, -2.0f, 0.5f, volume};
  xsph_viscosity(pos.data(), vel.data(), nb.span(), n, h, 0.5f, vx.data(), vy.data(), vz.data());
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_FLOAT_EQ(vx[i], 1.0f);
    EXPECT_FLOAT_EQ(vy[i], -2.0f);
    EXPECT_FLOAT_EQ(vz[i], 0.5f);
  }
}

TEST(Vorticity, RigidRotationHasVorticityTwiceTheAngularVelocity) {
  // v = Omega x r with Omega = (0, 0, 3): curl v = 2 Omega. Check an interior particle.
  const float s = 0.1f, h = 2 * s;
  std::vector<Float4> pos = lattice(9, s, 0.0f);
  const std::size_t n = pos.size();
  BruteNeighbors nb(pos, h);
  const float volume = float(1.0 / lattice_kernel_sum(s, h));  // consistent SPH volume (units of s^3)
  std::vector<Float4> vel(n);
  for (std::size_t i = 0; i < n; ++i) vel[i] = {-3.0f * pos[i].y, 3.0f * pos[i].x, 0.0f, volume};
  std::vector<float> wx(n), wy(n), wz(n);
  compute_vorticity(pos.data(), vel.data(), nb.span(), n, h, wx.data(), wy.data(), wz.data());
  const std::size_t center = 4 * 81 + 4 * 9 + 4;
  EXPECT_NEAR(wz[center], 6.0f, 0.6f);
  EXPECT_NEAR(wx[center], 0.0f, 1e-3f);
  EXPECT_NEAR(wy[center], 0.0f, 1e-3f);
}

// ---- Collisions -------------------------------------------------------------------------------------

TEST(Collisions, ShapesPushParticlesOutAndDomainHoldsThem) {
  Particles p(4);
  p.set(0, 0.5f, -0.1f, 0.5f);      // below the floor plane y = 0
  p.set(1, 0.52f, 0.5f, 0.5f);      // inside the sphere at (0.5, 0.5, 0.5), r = 0.1
  p.set(2, 0.81f, 0.85f, 0.85f);    // inside the box [0.8, 0.9]^3 (closest face x = 0.8)
  p.set(3, 5.0f, 0.5f, -3.0f);      // far outside the domain
  CollisionShape floor, ball, box;
  floor.kind = CollisionShape::Kind::Plane;
  ball.kind = CollisionShape::Kind::Sphere;
  ball.a[0] = ball.a[1] = ball.a[2] = 0.5f;
  ball.radius = 0.1f;
  box.kind = CollisionShape::Kind::Box;
  box.a[0] = box.a[1] = box.a[2] = 0.8f;
  box.b[0] = box.b[1] = box.b[2] = 0.9f;
  const CollisionShape shapes[] = {floor, ball, box};
  CollisionParams params;
  solve_collisions(p.view(), params, shapes);
  EXPECT_NEAR(p.py[0], 0.0f, 1e-6f);
  const float d1 = std::hypot(p.px[1] - 0.5f, p.py[1] - 0.5f, p.pz[1] - 0.5f);
  EXPECT_NEAR(d1, 0.1f, 1e-5f);
  EXPECT_NEAR(p.px[2], 0.8f, 1e-6f);
  EXPECT_EQ(p.px[3], 1.0f);
  EXPECT_EQ(p.pz[3], 0.0f);
}

TEST(Collisions, FrictionStopsSmallSlidingAndSlowsLargeSliding) {
  // A particle sinking 1 cm into the floor while moving sideways: with mu d >= the sideways
  // motion it sticks, otherwise the sideways motion shrinks by exactly mu d.
  CollisionShape floor;
  floor.kind = CollisionShape::Kind::Plane;
  floor.friction = 0.5f;
  CollisionParams params;
  params.domain_min[0] = params.domain_min[1] = params.domain_min[2] = -10.0f;
  params.domain_max[0] = params.domain_max[1] = params.domain_max[2] = 10.0f;
  const CollisionShape shapes[] = {floor};
  for (float slide : {0.004f, 0.05f}) {
    Particles p(1);
    p.x[0] = 0.0f, p.y[0] = 0.0f, p.z[0] = 0.0f;
    p.px[0] = slide, p.py[0] = -0.01f, p.pz[0] = 0.0f;
    solve_collisions(p.view(), params, shapes);
    const float expected = slide <= 0.5f * 0.01f ? 0.0f : slide - 0.5f * 0.01f;
    EXPECT_NEAR(p.px[0], expected, 1e-6f) << "slide " << slide;
    EXPECT_NEAR(p.py[0], 0.0f, 1e-6f);
  }
}

// The domain pass runs lane = particle with selects for the scalar branches: it must give every
// particle the bits of the plain scalar formulas (this reference, the kernel as it was written
// first), across mixed materials and radii, friction on and off, particles past several walls,
// pinned, NaN and infinite coordinates, and a count that leaves a partial last batch.
namespace domain_reference {

struct Point {
  float x, y, z;
};
void resolve_contact(Point& p, const Point& x, const float n[3], float depth, float mu) {
  p.x += depth * n[0];
  p.y += depth * n[1];
  p.z += depth * n[2];
  if (mu <= 0.0f) return;
  const float dx = p.x - x.x, dy = p.y - x.y, dz = p.z - x.z;
  const float dn = dx * n[0] + dy * n[1] + dz * n[2];
  const float tx = dx - dn * n[0], ty = dy - dn * n[1], tz = dz - dn * n[2];
  const float t_len = std::sqrt(tx * tx + ty * ty + tz * tz);
  if (t_len <= 0.0f) return;
  const float keep = t_len <= mu * depth ? 1.0f : mu * depth / t_len;
  p.x -= keep * tx;
  p.y -= keep * ty;
  p.z -= keep * tz;
}
void collide_domain(Point& p, const Point& x, const CollisionParams& c, float r) {
  float* pc[3] = {&p.x, &p.y, &p.z};
  for (int axis = 0; axis < 3; ++axis) {
    const float lo = c.domain_min[axis] + r;
    const float hi = std::max(c.domain_max[axis] - r, lo);
    float n[3] = {0, 0, 0};
    const float v = *pc[axis];
    if (v < lo) {
      n[axis] = 1.0f;
      resolve_contact(p, x, n, lo - v, c.domain_friction);
      *pc[axis] = lo;
    } else if (v > hi) {
      n[axis] = -1.0f;
      resolve_contact(p, x, n, v - hi, c.domain_friction);
      *pc[axis] = hi;
    }
  }
}
}  // namespace domain_reference

TEST(Collisions, DomainPassMatchesTheScalarReferenceBitForBit) {
  const std::size_t n = 9003;  // three tasks of the kernel's parallel loop, a partial last batch
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> pos(-0.3f, 1.3f), move(-0.4f, 0.4f), unit(0.0f, 1.0f);
  std::uniform_int_distribution<int> run_length(1, 20), kind(0, 3);
  // Raw particles, fluid, two cloths: the last wider than half the domain.
  const float radii[4] = {0.0f, 0.05f, 0.02f, 0.6f};
  Particles p(n);
  for (std::size_t i = 0; i < n;) {  // runs of one radius, so batches are uniform or mixed
    const float r = radii[kind(rng)];
    for (int k = run_length(rng); k > 0 && i < n; --k, ++i) {
      p.set(i, pos(rng), pos(rng), pos(rng));
      p.px[i] += move(rng), p.py[i] += move(rng), p.pz[i] += move(rng);
      p.radius[i] = r;
      p.w[i] = unit(rng) < 0.05f ? 0.0f : 1.0f;
    }
  }
  p.px[10] = std::nanf(""), p.py[11] = INFINITY, p.pz[12] = -INFINITY, p.px[13] = -0.0f;
  p.x[14] = std::nanf("");
  for (float mu : {0.0f, 0.4f}) {
    CollisionParams params;
    params.domain_friction = mu;
    Particles expected = p, got = p;
    for (std::size_t i = 0; i < n; ++i) {
      if (expected.w[i] <= 0.0f) continue;
      domain_reference::Point q{expected.px[i], expected.py[i], expected.pz[i]};
      domain_reference::collide_domain(q, {expected.x[i], expected.y[i], expected.z[i]}, params,
                                       expected.radius[i]);
      expected.px[i] = q.x, expected.py[i] = q.y, expected.pz[i] = q.z;
    }
    solve_collisions(got.view(), params, {});
    std::size_t moved = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const float e[3] = {expected.px[i], expected.py[i], expected.pz[i]};
      const float g[3] = {got.px[i], got.py[i], got.pz[i]};
      for (int a = 0; a < 3; ++a) {
        const bool same = std::isnan(e[a]) ? std::isnan(g[a])
                                           : std::memcmp(&e[a], &g[a], sizeof(float)) == 0;
        ASSERT_TRUE(same) << "particle " << i << " axis " << a << " mu " << mu << ": " << g[a]
                          << " instead of " << e[a];
      }
      moved += e[0] != p.px[i] || e[1] != p.py[i] || e[2] != p.pz[i];
    }
    EXPECT_GT(moved, n / 4) << "most contacts must be exercised";
  }
}

TEST(Collisions, PinnedParticlesStayAndNaNIsNotHidden) {
  Particles p(2);
  p.set(0, -1.0f, -1.0f, -1.0f);
  p.w[0] = 0.0f;  // pinned: not moved, even outside
  p.set(1, 0.5f, 0.5f, 0.5f);
  p.px[1] = std::nanf("");
  CollisionParams params;
  solve_collisions(p.view(), params, {});
  EXPECT_EQ(p.px[0], -1.0f);
  EXPECT_TRUE(std::isnan(p.px[1]));  // the run's finite check reports it
}

// ---- Blocked reductions -----------------------------------------------------------------------

// The sum of values of very different magnitudes depends on the order of the additions: the
// blocked reduction adds each block in index order and the blocks in block order, with the same
// bits as that serial computation, with 1 and 2 threads and any block size.
TEST(BlockedReduce, SumsBlocksInIndexOrderThenBlocksInOrder) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> mantissa(1.0, 2.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  const std::size_t n = 3 * kReduceBlock + 17;  // three full blocks and a partial one
  std::vector<double> v(n);
  for (double& x : v) x = std::ldexp(mantissa(rng), exponent(rng)) * (rng() % 2 ? 1.0 : -1.0);
  const auto reduce = [&](std::size_t block) {
    return blocked_reduce(
        n, 0.0,
        [&](std::size_t b, std::size_t e) {
          double s = 0.0;
          for (std::size_t i = b; i < e; ++i) s += v[i];
          return s;
        },
        [](double& acc, double s) { acc += s; }, block);
  };
  for (const std::size_t block : {kReduceBlock, std::size_t(1000), std::size_t(1)}) {
    double expected = 0.0;
    for (std::size_t b = 0; b < n; b += block) {
      double s = 0.0;
      for (std::size_t i = b; i < std::min(n, b + block); ++i) s += v[i];
      expected += s;
    }
    for (const int threads : {1, 2}) {
      const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      const double got = reduce(block);
      EXPECT_EQ(std::memcmp(&got, &expected, sizeof got), 0)
          << "block " << block << ", " << threads << " threads: " << got << " vs " << expected;
    }
  }
  // An empty range is the identity; a max combines like a sum.
  EXPECT_EQ(blocked_reduce(
                0, 7.0, [](std::size_t, std::size_t) { return 1.0; },
                [](double& acc, double s) { acc += s; }),
            7.0);
  const double max = blocked_reduce(
      n, 0.0,
      [&](std::size_t b, std::size_t e) {
        double m = 0.0;
        for (std::size_t i = b; i < e; ++i) m = std::max(m, v[i]);
        return m;
      },
      [](double& acc, double m) { acc = std::max(acc, m); });
  EXPECT_EQ(max, *std::max_element(v.begin(), v.end()));
}
