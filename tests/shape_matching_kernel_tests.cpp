// Shape matching kernels (kernels/shape_matching.hpp, shape_plasticity.hpp): the closest
// rotation against known polar decompositions, degenerate and reflected inputs; one projection
// of a deformed cluster against the rigid-body invariants (rest distances, centre of mass,
// momentum); the linear goal against a shear, a stretch and a crush; degenerate clusters (a line, a
// plane, one point) never give NaN; plastic flow above the yield only, bounded; overlapping
// clusters keep the momentum.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "seiche/kernels/shape_matching.hpp"
#include "seiche/kernels/shape_plasticity.hpp"

using namespace seiche::kernels;

namespace {

// Row-major rotation matrix of a unit quaternion (x, y, z, w), in double.
void rotation_matrix(const Quaternion& q, double r[9]) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  r[0] = 1 - 2 * (y * y + z * z), r[1] = 2 * (x * y - w * z), r[2] = 2 * (x * z + w * y);
  r[3] = 2 * (x * y + w * z), r[4] = 1 - 2 * (x * x + z * z), r[5] = 2 * (y * z - w * x);
  r[6] = 2 * (x * z - w * y), r[7] = 2 * (y * z + w * x), r[8] = 1 - 2 * (x * x + y * y);
}

Quaternion axis_angle(double ax, double ay, double az, double angle) {
  const double n = std::sqrt(ax * ax + ay * ay + az * az);
  const double s = std::sin(angle / 2) / n;
  return {float(ax * s), float(ay * s), float(az * s), float(std::cos(angle / 2))};
}

void multiply(const double a[9], const double b[9], double out[9]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      out[3 * i + j] = 0;
      for (int k = 0; k < 3; ++k) out[3 * i + j] += a[3 * i + k] * b[3 * k + j];
    }
}

double max_difference(const double a[9], const double b[9]) {
  double d = 0;
  for (int k = 0; k < 9; ++k) d = std::max(d, std::fabs(a[k] - b[k]));
  return d;
}

double determinant(const double r[9]) {
  return r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
         r[2] * (r[3] * r[7] - r[4] * r[6]);
}

}  // namespace

TEST(ShapeMatching, ClosestRotationRecoversThePolarFactor) {
  // A = R0 S with S symmetric positive definite: the closest rotation is R0, from any start,
  // whatever the scale of A.
  const Quaternion truth = axis_angle(0.3, -1.0, 0.5, 2.6);  // 149 degrees
  double r0[9];
  rotation_matrix(truth, r0);
  const double s[9] = {2.0, 0.3, -0.1, 0.3, 1.2, 0.2, -0.1, 0.2, 0.7};
  double a[9];
  multiply(r0, s, a);
  for (double scale : {1.0, 1e-9, 1e9}) {
    double scaled[9];
    for (int k = 0; k < 9; ++k) scaled[k] = a[k] * scale;
    for (const Quaternion& guess : {kIdentityRotation, axis_angle(1, 1, 0, 1.0), truth}) {
      double r[9];
      rotation_matrix(closest_rotation(scaled, guess), r);
      EXPECT_LT(max_difference(r, r0), 2e-6) << "scale " << scale;
    }
  }
}

TEST(ShapeMatching, DegenerateInputsKeepAProperRotationAndNeverNaN) {
  const Quaternion guess = axis_angle(0, 0, 1, 0.4);
  double g[9];
  rotation_matrix(guess, g);
  // A = 0 (a one-particle cluster) and a non-finite A: the previous rotation.
  const double zero[9] = {};
  double r[9];
  rotation_matrix(closest_rotation(zero, guess), r);
  EXPECT_LT(max_difference(r, g), 1e-7);
  const double nan[9] = {std::nan(""), 0, 0, 0, 1, 0, 0, 0, 1};
  const Quaternion from_nan = closest_rotation(nan, guess);
  for (float v : from_nan) EXPECT_TRUE(std::isfinite(v));
  // A flat cluster rotated by 90 degrees about z (A has rank 2: no extent along z): the rotation
  // about z is recovered exactly, the out-of-plane part stays proper.
  const double flat[9] = {0, -1, 0, 1, 0, 0, 0, 0, 0};
  rotation_matrix(closest_rotation(flat, kIdentityRotation), r);
  const double quarter_turn[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
  EXPECT_LT(max_difference(r, quarter_turn), 1e-6);
  // A linear cluster (rank 1) along x turned onto y: x goes to y, det stays +1.
  const double line[9] = {0, 0, 0, 1, 0, 0, 0, 0, 0};
  rotation_matrix(closest_rotation(line, kIdentityRotation), r);
  EXPECT_NEAR(r[3], 1.0, 1e-6);  // R e_x = e_y
  EXPECT_NEAR(determinant(r), 1.0, 1e-6);
  // A reflection (det A < 0): still a proper rotation.
  const double mirror[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1};
  rotation_matrix(closest_rotation(mirror, guess), r);
  EXPECT_NEAR(determinant(r), 1.0, 1e-6);
  for (double v : r) EXPECT_TRUE(std::isfinite(v));
}

namespace {

// A 3 x 3 x 2 lattice cluster with unequal masses, its rest offsets and SoA columns.
struct Cluster {
  std::vector<float> x, y, z, px, py, pz, vx, vy, vz, w;
  ShapeClusters clusters;
  Cluster() {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 2; ++k) {
          x.push_back(0.1f * i), y.push_back(0.1f * j), z.push_back(0.1f * k);
          w.push_back(1.0f / (1.0f + 0.5f * float((i + j + k) % 3)));
        }
    const std::size_t n = x.size();
    double mass = 0, c[3] = {0, 0, 0};
    for (std::size_t i = 0; i < n; ++i) {
      mass += 1.0 / w[i];
      c[0] += x[i] / w[i], c[1] += y[i] / w[i], c[2] += z[i] / w[i];
    }
    clusters.begin_cluster(1.0f);
    for (std::size_t i = 0; i < n; ++i)
      clusters.add_member(std::uint32_t(i), float(x[i] - c[0] / mass), float(y[i] - c[1] / mass),
                          float(z[i] - c[2] / mass));
    clusters.end_cluster();
    clusters.finish();
    px = x, py = y, pz = z, vx.assign(n, 0), vy.assign(n, 0), vz.assign(n, 0);
  }
  ParticleView view() {
    ParticleView v;
    v.n = x.size();
    v.x = x.data(), v.y = y.data(), v.z = z.data(), v.px = px.data(), v.py = py.data(), v.pz = pz.data();
    v.vx = vx.data(), v.vy = vy.data(), v.vz = vz.data(), v.w = w.data();
    return v;
  }
  // Predicted positions p = M x + t of the rest lattice.
  void deform(const double m[9], const double t[3]) {
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double q[3] = {x[i], y[i], z[i]};
      px[i] = float(m[0] * q[0] + m[1] * q[1] + m[2] * q[2] + t[0]);
      py[i] = float(m[3] * q[0] + m[4] * q[1] + m[5] * q[2] + t[1]);
      pz[i] = float(m[6] * q[0] + m[7] * q[1] + m[8] * q[2] + t[2]);
    }
  }
};
}  // namespace

TEST(ShapeMatching, RigidProjectionRestoresTheShapeAndKeepsMomentum) {
  Cluster c;
  const std::size_t n = c.x.size();
  // Rotate the lattice by 120 degrees, move it, and shake every particle.
  const Quaternion turn = axis_angle(1, 2, 3, 2.1);
  double r[9];
  rotation_matrix(turn, r);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> noise(-0.02f, 0.02f);
  for (std::size_t i = 0; i < n; ++i) {
    const double q[3] = {c.x[i], c.y[i], c.z[i]};
    c.px[i] = float(r[0] * q[0] + r[1] * q[1] + r[2] * q[2] + 1.0) + noise(rng);
    c.py[i] = float(r[3] * q[0] + r[4] * q[1] + r[5] * q[2] - 2.0) + noise(rng);
    c.pz[i] = float(r[6] * q[0] + r[7] * q[1] + r[8] * q[2] + 0.5) + noise(rng);
  }
  auto weighted_sum = [&](const std::vector<float>& v) {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += v[i] / c.w[i];
    return s;
  };
  const double before[3] = {weighted_sum(c.px), weighted_sum(c.py), weighted_sum(c.pz)};
  solve_shape_matching(c.view(), c.clusters);
  // Every pairwise distance is the rest distance: the cluster is rigid again.
  double worst = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      const double rest = std::hypot(c.x[i] - c.x[j], c.y[i] - c.y[j], c.z[i] - c.z[j]);
      const double now = std::hypot(c.px[i] - c.px[j], c.py[i] - c.py[j], c.pz[i] - c.pz[j]);
      worst = std::max(worst, std::fabs(now - rest));
    }
  EXPECT_LT(worst, 1e-6);
  // The centre of mass (the momentum of the correction) did not move.
  const double after[3] = {weighted_sum(c.px), weighted_sum(c.py), weighted_sum(c.pz)};
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(after[a], before[a], 1e-5);
  // The rotation found is close to the one applied (the noise is small).
  double found[9];
  rotation_matrix(c.clusters.rotation[0], found);
  EXPECT_LT(max_difference(found, r), 0.1);
  // A second projection of the rigid result moves nothing (within rounding).
  const std::vector<float> px = c.px;
  solve_shape_matching(c.view(), c.clusters);
  for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(c.px[i], px[i], 1e-6);
}

TEST(ShapeMatching, SoftStiffnessMovesPartWayAndPinnedMembersStay) {
  Cluster c;
  c.px[0] += 0.05f;  // dent one corner
  Cluster rigid = c;
  c.clusters.stiffness = {0.25f};
  solve_shape_matching(c.view(), c.clusters);
  solve_shape_matching(rigid.view(), rigid.clusters);
  // A quarter of the way to the rigid goal.
  const float dented = 0.05f;
  EXPECT_NEAR(c.px[0] - 0.0f, 0.75f * (dented - 0.0f) + 0.25f * (rigid.px[0] - 0.0f), 1e-6);
  // A pinned member is not moved and weighs nothing.
  Cluster pinned;
  pinned.px[5] += 0.05f;
  pinned.w[5] = 0.0f;
  const float held = pinned.px[5];
  solve_shape_matching(pinned.view(), pinned.clusters);
  EXPECT_EQ(pinned.px[5], held);
}

TEST(ShapeMatching, LinearBlendFollowsTheLinearFit) {
  // A shear (det 1) and a shift: the linear fit of the cluster is the shear itself.
  const double shear[9] = {1, 0.3, 0, 0, 1, 0, 0, 0, 1};
  const double shift[3] = {0.5, 0.2, -0.1};
  Cluster linear, rigid, half;
  for (Cluster* c : {&linear, &rigid, &half}) c->deform(shear, shift);
  const std::vector<float> sheared_x = linear.px, sheared_y = linear.py;
  linear.clusters.linear_blend = {1.0f};
  half.clusters.linear_blend = {0.5f};
  solve_shape_matching(linear.view(), linear.clusters);
  solve_shape_matching(rigid.view(), rigid.clusters);
  solve_shape_matching(half.view(), half.clusters);
  const std::size_t n = linear.x.size();
  double worst_linear = 0, worst_half = 0, worst_rigid = 0;
  for (std::size_t i = 0; i < n; ++i) {
    // beta 1: every goal is where the particle is (the shear is a goal).
    worst_linear = std::max({worst_linear, std::fabs(double(linear.px[i]) - sheared_x[i]),
                             std::fabs(double(linear.py[i]) - sheared_y[i])});
    // beta 1/2: halfway between the shear and the rigid goal.
    worst_half = std::max({worst_half, std::fabs(half.px[i] - 0.5 * (sheared_x[i] + rigid.px[i])),
                           std::fabs(half.py[i] - 0.5 * (sheared_y[i] + rigid.py[i]))});
    // beta 0: rigid (the distances are the rest distances).
    for (std::size_t j = i + 1; j < n; ++j) {
      const double rest = std::hypot(rigid.x[i] - rigid.x[j], rigid.y[i] - rigid.y[j], rigid.z[i] - rigid.z[j]);
      const double now = std::hypot(rigid.px[i] - rigid.px[j], rigid.py[i] - rigid.py[j], rigid.pz[i] - rigid.pz[j]);
      worst_rigid = std::max(worst_rigid, std::fabs(now - rest));
    }
  }
  EXPECT_LT(worst_linear, 2e-7);
  EXPECT_LT(worst_half, 2e-7);
  EXPECT_LT(worst_rigid, 1e-6);
  EXPECT_GT(std::fabs(rigid.px[n - 1] - sheared_x[n - 1]), 0.01);  // the rigid goal is elsewhere

  // A stretch by 1.2 along x (det 1.2): the goal keeps the volume, x scaled by 1.2^(2/3) and
  // y, z by 1.2^(-1/3), about the centre of mass.
  Cluster stretched;
  const double stretch[9] = {1.2, 0, 0, 0, 1, 0, 0, 0, 1}, none[3] = {0, 0, 0};
  stretched.deform(stretch, none);
  stretched.clusters.linear_blend = {1.0f};
  solve_shape_matching(stretched.view(), stretched.clusters);
  const double k = std::cbrt(1.2);
  for (std::size_t i = 0; i < n; ++i) {
    const double qx = stretched.clusters.rest_x[i], qy = stretched.clusters.rest_y[i];
    const double cx = stretched.x[i] - qx, cy = stretched.y[i] - qy;  // the rest centre of mass
    EXPECT_NEAR(stretched.px[i], 1.2 * cx + 1.2 / k * qx, 1e-6);
    EXPECT_NEAR(stretched.py[i], cy + qy / k, 1e-6);
  }
}

TEST(ShapeMatching, ACrushedClusterGetsTheRigidGoal) {
  // Squashed to a twentieth of its height (det A = 0.05, below 1/8): rescaled to its volume the
  // linear fit would throw the goals 2.7 times as far out; the goal is the rigid one instead.
  const double crush[9] = {1, 0, 0, 0, 0.05, 0, 0, 0, 1}, none[3] = {0, 0, 0};
  Cluster linear, rigid;
  for (Cluster* c : {&linear, &rigid}) c->deform(crush, none);
  linear.clusters.linear_blend = {1.0f};
  solve_shape_matching(linear.view(), linear.clusters);
  solve_shape_matching(rigid.view(), rigid.clusters);
  for (std::size_t i = 0; i < linear.x.size(); ++i) {
    EXPECT_EQ(linear.px[i], rigid.px[i]);
    EXPECT_EQ(linear.py[i], rigid.py[i]);
  }
  // Squashed to half (det 0.5): the linear goal keeps the squash, at the rest volume.
  const double half[9] = {1, 0, 0, 0, 0.5, 0, 0, 0, 1};
  Cluster squashed;
  squashed.deform(half, none);
  squashed.clusters.linear_blend = {1.0f};
  solve_shape_matching(squashed.view(), squashed.clusters);
  const double k = std::cbrt(0.5);
  const std::size_t top = squashed.x.size() - 1;  // (0.2, 0.2, 0.1)
  const double cy = squashed.y[top] - squashed.clusters.rest_y[top];
  EXPECT_NEAR(squashed.py[top], 0.5 * cy + 0.5 / k * squashed.clusters.rest_y[top], 1e-6);
}

TEST(ShapeMatching, DegenerateClustersNeverGiveNaN) {
  // Collinear, coplanar, coincident and one-particle clusters, each linear and plastic, their
  // predicted positions shaken off the line and the plane, then collapsed onto one point.
  auto make = [](const std::vector<std::array<float, 3>>& rest) {
    Cluster c;
    c.x.clear(), c.y.clear(), c.z.clear(), c.w.assign(rest.size(), 1.0f);
    c.clusters = ShapeClusters{};
    c.clusters.begin_cluster(1.0f);
    double mean[3] = {0, 0, 0};
    for (const auto& r : rest) mean[0] += r[0], mean[1] += r[1], mean[2] += r[2];
    for (std::size_t i = 0; i < rest.size(); ++i) {
      c.x.push_back(rest[i][0]), c.y.push_back(rest[i][1]), c.z.push_back(rest[i][2]);
      c.clusters.add_member(std::uint32_t(i), float(rest[i][0] - mean[0] / double(rest.size())),
                            float(rest[i][1] - mean[1] / double(rest.size())),
                            float(rest[i][2] - mean[2] / double(rest.size())));
    }
    c.clusters.end_cluster();
    c.clusters.finish();
    c.clusters.linear_blend = {1.0f};
    c.clusters.plasticity = {Plasticity{0.0f, 100.0f, 0.5f}};
    c.px = c.x, c.py = c.y, c.pz = c.z;
    c.vx.assign(rest.size(), 0), c.vy.assign(rest.size(), 0), c.vz.assign(rest.size(), 0);
    return c;
  };
  std::vector<std::vector<std::array<float, 3>>> shapes = {
      {{0, 0, 0}, {0.1f, 0, 0}, {0.2f, 0, 0}, {0.3f, 0, 0}, {0.4f, 0, 0}},               // a line
      {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}, {0.1f, 0.1f, 0}, {0.2f, 0.1f, 0}},        // a plane
      {{0.3f, 0.3f, 0.3f}, {0.3f, 0.3f, 0.3f}, {0.3f, 0.3f, 0.3f}, {0.3f, 0.3f, 0.3f}},  // one point
      {{0.5f, 0.5f, 0.5f}},                                                              // one particle
  };
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> noise(-0.03f, 0.03f);
  for (std::size_t shape = 0; shape < shapes.size(); ++shape) {
    Cluster c = make(shapes[shape]);
    for (int round = 0; round < 20; ++round) {
      for (std::size_t i = 0; i < c.x.size(); ++i) {
        if (round == 10) c.px[i] = c.py[i] = c.pz[i] = 0.25f;  // collapsed: A = 0
        else c.px[i] += noise(rng), c.py[i] += noise(rng), c.pz[i] += noise(rng);
      }
      solve_shape_matching(c.view(), c.clusters);
      update_shape_plasticity(c.view(), c.clusters, 0.01f);
      EXPECT_TRUE(std::isfinite(shape_strain(c.view(), c.clusters, 0)));
      for (std::size_t i = 0; i < c.x.size(); ++i)
        ASSERT_TRUE(std::isfinite(c.px[i]) && std::isfinite(c.py[i]) && std::isfinite(c.pz[i]))
            << "shape " << shape << " round " << round;
      for (float v : c.clusters.rotation[0]) ASSERT_TRUE(std::isfinite(v));
    }
    // The linear map of a flat, linear or coincident cluster is undefined: no plastic flow.
    for (int k = 0; k < 9; ++k) EXPECT_EQ(c.clusters.plastic[0][k], kIdentityMatrix[k]) << "shape " << shape;
  }
}

TEST(ShapeMatching, PlasticFlowAboveTheYieldOnlyAndBounded) {
  // A volume-keeping stretch diag(1.25, 0.8, 1): S - I = diag(0.25, -0.2, 0), |S - I| = 0.3202.
  const double stretch[9] = {1.25, 0, 0, 0, 0.8, 0, 0, 0, 1}, none[3] = {0, 0, 0};
  const double strain = std::hypot(0.25, 0.2);
  Cluster below, above, clamped;
  for (Cluster* c : {&below, &above, &clamped}) c->deform(stretch, none);
  EXPECT_NEAR(shape_strain(below.view(), below.clusters, 0), strain, 1e-6);
  below.clusters.plasticity = {Plasticity{float(strain + 0.01), 10.0f, 1.0f}};
  update_shape_plasticity(below.view(), below.clusters, 0.01f);
  for (int k = 0; k < 9; ++k) EXPECT_EQ(below.clusters.plastic[0][k], kIdentityMatrix[k]);  // to the bit

  above.clusters.plasticity = {Plasticity{float(strain - 0.01), 10.0f, 1.0f}};
  update_shape_plasticity(above.view(), above.clusters, 0.01f);
  // Sp = (I + 0.1 (S - I)) / det^(1/3) = diag(1.025, 0.98, 1) / (1.0045)^(1/3).
  const double k = std::cbrt(1.025 * 0.98);
  const Matrix3& sp = above.clusters.plastic[0];
  EXPECT_NEAR(sp[0], 1.025 / k, 1e-6);
  EXPECT_NEAR(sp[4], 0.98 / k, 1e-6);
  EXPECT_NEAR(sp[8], 1.0 / k, 1e-6);
  for (int off : {1, 2, 3, 5, 6, 7}) EXPECT_NEAR(sp[off], 0.0, 1e-6);
  // The rest shape moved toward the stretch: its strain is smaller now.
  EXPECT_LT(shape_strain(above.view(), above.clusters, 0), strain - 0.02);

  // A fast creep is bounded by max_strain (before the volume correction, which adds little).
  clamped.clusters.plasticity = {Plasticity{0.0f, 1000.0f, 0.1f}};
  update_shape_plasticity(clamped.view(), clamped.clusters, 0.01f);
  double e2 = 0;
  for (int m = 0; m < 9; ++m) e2 += std::pow(clamped.clusters.plastic[0][m] - kIdentityMatrix[m], 2);
  EXPECT_NEAR(std::sqrt(e2), 0.1, 0.01);
}

TEST(ShapeMatching, OverlappingClustersAverageTheirGoalsAndKeepMomentum) {
  // The 3 x 3 x 2 lattice as two clusters sharing the middle layer x = 0.1 (each of its
  // particles weighs half its mass in each).
  Cluster c;
  const std::size_t n = c.x.size();
  ShapeClusters two;
  for (int side = 0; side < 2; ++side) {
    std::vector<std::uint32_t> members;
    for (std::uint32_t i = 0; i < n; ++i)
      if ((side == 0 && c.x[i] < 0.15f) || (side == 1 && c.x[i] > 0.05f)) members.push_back(i);
    auto share = [&](std::uint32_t i) { return (c.x[i] > 0.05f && c.x[i] < 0.15f) ? 0.5 : 1.0; };
    double mass = 0, centre[3] = {0, 0, 0};
    for (std::uint32_t i : members) {
      const double m = share(i) / c.w[i];
      mass += m, centre[0] += m * c.x[i], centre[1] += m * c.y[i], centre[2] += m * c.z[i];
    }
    two.begin_cluster(1.0f);
    two.overlapping.back() = 1;
    for (std::uint32_t i : members)
      two.add_member(i, float(c.x[i] - centre[0] / mass), float(c.y[i] - centre[1] / mass),
                     float(c.z[i] - centre[2] / mass), float(share(i)));
    two.end_cluster();
  }
  two.shared_start = {0};
  for (std::uint32_t i = 0; i < n; ++i) {
    for (std::uint32_t k = 0; k < two.members(); ++k)
      if (two.particle[k] == i) two.shared_member.push_back(k);
    two.shared_particle.push_back(i);
    two.shared_start.push_back(std::uint32_t(two.shared_member.size()));
    two.shared_stiffness.push_back(1.0f);
  }
  two.finish();
  // Rotated rigidly: every goal is where the particle is.
  const Quaternion turn = axis_angle(0, 1, 1, 0.7);
  double r[9];
  rotation_matrix(turn, r);
  const double shift[3] = {0.2, 0.1, 0.0};
  c.deform(r, shift);
  const std::vector<float> rotated = c.px;
  solve_shape_matching(c.view(), two);
  for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(c.px[i], rotated[i], 1e-6);
  // Shaken: the momentum of the correction is zero, and a bent shape straightens.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> noise(-0.02f, 0.02f);
  for (std::size_t i = 0; i < n; ++i) c.px[i] += noise(rng), c.py[i] += noise(rng), c.pz[i] += noise(rng);
  auto momentum = [&](const std::vector<float>& v) {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += v[i] / c.w[i];
    return s;
  };
  auto worst_distance_error = [&] {
    double worst = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j)
        worst = std::max(worst, double(std::fabs(std::hypot(c.px[i] - c.px[j], c.py[i] - c.py[j], c.pz[i] - c.pz[j]) -
                                          std::hypot(c.x[i] - c.x[j], c.y[i] - c.y[j], c.z[i] - c.z[j]))));
    return worst;
  };
  const double before[3] = {momentum(c.px), momentum(c.py), momentum(c.pz)};
  const double error_before = worst_distance_error();
  solve_shape_matching(c.view(), two);
  EXPECT_NEAR(momentum(c.px), before[0], 1e-5);
  EXPECT_NEAR(momentum(c.py), before[1], 1e-5);
  EXPECT_NEAR(momentum(c.pz), before[2], 1e-5);
  EXPECT_LT(worst_distance_error(), 0.5 * error_before);
}
