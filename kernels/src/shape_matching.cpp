// Shape matching (shape_matching.hpp; Müller et al. 2005):
//   c = sum m_i p_i / M,  A = sum m_i (p_i - c) q_i^T,  R = rot(A),  p_i += s (c + R q_i - p_i)
// and the closest rotation by the iteration of Müller et al. 2016: with R's columns r_j and A's
// columns a_j, the rotation that maximises tr(R^T A) makes sum_j r_j x a_j vanish, so
//   omega = sum_j r_j x a_j / (|sum_j r_j . a_j| + eps),   R <- rotation by omega, R
// until |omega| is tiny. The step uses the quaternion (omega / 2, 1) normalised, which turns by
// 2 atan(|omega| / 2) instead of |omega|: the same fixed point, reached in a few more steps, and
// only + - * / sqrt (correctly rounded everywhere), so every machine gets the same bits, as no
// libm sin/cos is involved. Sums and the rotation are in double; the store stays float.
//
// Hand-written 3 x 3 and quaternion algebra instead of Eigen: the kernel layer does not depend
// on Eigen, and whether a library picks a SIMD path for a 3 x 3 product would be one more thing
// that could make the bits differ between builds.
#include "seiche/kernels/shape_matching.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

namespace seiche::kernels {

namespace {

constexpr int kMaxRotationSteps = 64;
constexpr double kStationary = 1e-9;  // |omega| below this (A scaled to unit norm): converged

struct Quat {
  double x, y, z, w;
};

Quat normalized(const Quat& q) {
  const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(n > 0.0) || !std::isfinite(n)) return {0.0, 0.0, 0.0, 1.0};
  return {q.x / n, q.y / n, q.z / n, q.w / n};
}

// a * b: first b, then a.
Quat multiply(const Quat& a, const Quat& b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
          a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

// The rotation matrix of a unit quaternion, row-major.
void to_matrix(const Quat& q, double r[9]) {
  const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
  const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  r[0] = 1.0 - 2.0 * (yy + zz), r[1] = 2.0 * (xy - wz), r[2] = 2.0 * (xz + wy);
  r[3] = 2.0 * (xy + wz), r[4] = 1.0 - 2.0 * (xx + zz), r[5] = 2.0 * (yz - wx);
  r[6] = 2.0 * (xz - wy), r[7] = 2.0 * (yz + wx), r[8] = 1.0 - 2.0 * (xx + yy);
}

Quat closest_rotation_double(const double a_in[9], Quat q) {
  double norm2 = 0.0;
  for (int k = 0; k < 9; ++k) norm2 += a_in[k] * a_in[k];
  const double norm = std::sqrt(norm2);
  q = normalized(q);
  if (!(norm > 0.0) || !std::isfinite(norm)) return q;  // A says nothing (or is not finite)
  double a[9];
  for (int k = 0; k < 9; ++k) a[k] = a_in[k] / norm;
  for (int step = 0; step < kMaxRotationSteps; ++step) {
    double r[9];
    to_matrix(q, r);
    double omega[3] = {0.0, 0.0, 0.0}, dot = 0.0;
    for (int j = 0; j < 3; ++j) {  // column j of R and of A
      const double rj[3] = {r[j], r[3 + j], r[6 + j]};
      const double aj[3] = {a[j], a[3 + j], a[6 + j]};
      omega[0] += rj[1] * aj[2] - rj[2] * aj[1];
      omega[1] += rj[2] * aj[0] - rj[0] * aj[2];
      omega[2] += rj[0] * aj[1] - rj[1] * aj[0];
      dot += rj[0] * aj[0] + rj[1] * aj[1] + rj[2] * aj[2];
    }
    const double scale = 1.0 / (std::fabs(dot) + kStationary);
    for (double& o : omega) o *= scale;
    const double length2 = omega[0] * omega[0] + omega[1] * omega[1] + omega[2] * omega[2];
    if (!(length2 > kStationary * kStationary)) break;  // converged (NaN cannot get here)
    q = normalized(multiply({0.5 * omega[0], 0.5 * omega[1], 0.5 * omega[2], 1.0}, q));
  }
  return q;
}

void match_cluster(const ParticleView& p, const RestOffsets& rest, ShapeClusters& s, std::size_t c) {
  const std::uint32_t begin = s.start[c], end = s.start[c + 1];
  double mass = 0.0, centre[3] = {0.0, 0.0, 0.0};
  for (std::uint32_t k = begin; k < end; ++k) {
    const std::uint32_t i = s.particle[k];
    if (!(p.w[i] > 0.0f)) continue;  // pinned: weighs nothing here
    const double m = 1.0 / double(p.w[i]);
    mass += m;
    centre[0] += m * p.px[i], centre[1] += m * p.py[i], centre[2] += m * p.pz[i];
  }
  if (!(mass > 0.0)) return;  // nothing movable
  for (double& v : centre) v /= mass;
  double a[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (std::uint32_t k = begin; k < end; ++k) {
    const std::uint32_t i = s.particle[k];
    if (!(p.w[i] > 0.0f)) continue;
    const double m = 1.0 / double(p.w[i]);
    const double d[3] = {m * (p.px[i] - centre[0]), m * (p.py[i] - centre[1]), m * (p.pz[i] - centre[2])};
    const double q[3] = {rest.x[i], rest.y[i], rest.z[i]};
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) a[3 * row + col] += d[row] * q[col];
  }
  const Quaternion& guess = s.rotation[c];
  const Quat rot = closest_rotation_double(a, {guess[0], guess[1], guess[2], guess[3]});
  s.rotation[c] = {float(rot.x), float(rot.y), float(rot.z), float(rot.w)};
  double r[9];
  to_matrix(rot, r);
  const double stiffness = s.stiffness[c];
  for (std::uint32_t k = begin; k < end; ++k) {
    const std::uint32_t i = s.particle[k];
    if (!(p.w[i] > 0.0f)) continue;
    const double q[3] = {rest.x[i], rest.y[i], rest.z[i]};
    float* pos[3] = {&p.px[i], &p.py[i], &p.pz[i]};
    for (int row = 0; row < 3; ++row) {
      const double goal = centre[row] + r[3 * row] * q[0] + r[3 * row + 1] * q[1] + r[3 * row + 2] * q[2];
      *pos[row] = float(*pos[row] + stiffness * (goal - *pos[row]));
    }
  }
}

}  // namespace

void ShapeClusters::remap(std::span<const std::uint32_t> new_index) {
  for (std::uint32_t& k : particle) k = new_index[k];
}

Quaternion closest_rotation(const double a[9], Quaternion guess) {
  const Quat q = closest_rotation_double(a, {guess[0], guess[1], guess[2], guess[3]});
  return {float(q.x), float(q.y), float(q.z), float(q.w)};
}

void solve_shape_matching(const ParticleView& p, const RestOffsets& rest, ShapeClusters& clusters) {
  // One cluster per task: its sums run in member order on one thread, so the result does not
  // depend on the thread count.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, clusters.clusters(), 1), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) match_cluster(p, rest, clusters, c);
  });
}

}  // namespace seiche::kernels
