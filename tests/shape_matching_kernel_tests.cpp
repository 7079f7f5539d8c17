// Shape matching kernel (kernels/shape_matching.hpp): the closest rotation against known
// polar decompositions, degenerate and reflected inputs; one projection of a deformed cluster
// against the rigid-body invariants (rest distances, centre of mass, momentum).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "seiche/kernels/shape_matching.hpp"

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
  std::vector<float> x, y, z, px, py, pz, vx, vy, vz, w, rx, ry, rz;
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
    for (std::size_t i = 0; i < n; ++i) {
      rx.push_back(float(x[i] - c[0] / mass)), ry.push_back(float(y[i] - c[1] / mass));
      rz.push_back(float(z[i] - c[2] / mass));
    }
    px = x, py = y, pz = z, vx.assign(n, 0), vy.assign(n, 0), vz.assign(n, 0);
    clusters.start = {0, std::uint32_t(n)};
    for (std::uint32_t i = 0; i < n; ++i) clusters.particle.push_back(i);
    clusters.stiffness = {1.0f};
    clusters.rotation = {kIdentityRotation};
  }
  ParticleView view() {
    ParticleView v;
    v.n = x.size();
    v.x = x.data(), v.y = y.data(), v.z = z.data(), v.px = px.data(), v.py = py.data(), v.pz = pz.data();
    v.vx = vx.data(), v.vy = vy.data(), v.vz = vz.data(), v.w = w.data();
    return v;
  }
  RestOffsets rest() const { return {rx.data(), ry.data(), rz.data()}; }
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
  solve_shape_matching(c.view(), c.rest(), c.clusters);
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
  solve_shape_matching(c.view(), c.rest(), c.clusters);
  for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(c.px[i], px[i], 1e-6);
}

TEST(ShapeMatching, SoftStiffnessMovesPartWayAndPinnedMembersStay) {
  Cluster c;
  c.px[0] += 0.05f;  // dent one corner
  Cluster rigid = c;
  c.clusters.stiffness = {0.25f};
  solve_shape_matching(c.view(), c.rest(), c.clusters);
  solve_shape_matching(rigid.view(), rigid.rest(), rigid.clusters);
  // A quarter of the way to the rigid goal.
  const float dented = 0.05f;
  EXPECT_NEAR(c.px[0] - 0.0f, 0.75f * (dented - 0.0f) + 0.25f * (rigid.px[0] - 0.0f), 1e-6);
  // A pinned member is not moved and weighs nothing.
  Cluster pinned;
  pinned.px[5] += 0.05f;
  pinned.w[5] = 0.0f;
  const float held = pinned.px[5];
  solve_shape_matching(pinned.view(), pinned.rest(), pinned.clusters);
  EXPECT_EQ(pinned.px[5], held);
}
