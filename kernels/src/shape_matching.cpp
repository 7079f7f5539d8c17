// Shape matching (shape_matching.hpp; Müller et al. 2005):
//   c = sum m_i p_i / M,  A = sum m_i (p_i - c) q_i^T,  R = rot(A),  p_i += s (c + T q_i - p_i)
// and the closest rotation by the iteration of Müller et al. 2016: with R's columns r_j and A's
// columns a_j, the rotation that maximises tr(R^T A) makes sum_j r_j x a_j vanish, so
//   omega = sum_j r_j x a_j / (|sum_j r_j . a_j| + eps),   R <- rotation by omega, R
// until |omega| is tiny. The step uses the quaternion (omega / 2, 1) normalised, which turns by
// 2 atan(|omega| / 2) instead of |omega|: the same fixed point, reached in a few more steps, and
// only + - * / sqrt (correctly rounded everywhere), so every machine gets the same bits, as no
// libm sin/cos is involved. Sums and the rotation are in double; the store stays float.
// The fit and the 3 x 3 algebra are in shape_fit.hpp.
#include "seiche/kernels/shape_matching.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

#include "shape_fit.hpp"

namespace seiche::kernels {

namespace shape_detail {

namespace {

constexpr int kMaxRotationSteps = 64;
constexpr double kStationary = 1e-9;  // |omega| below this (A scaled to unit norm): converged

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

}  // namespace

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

}  // namespace shape_detail

namespace {

using namespace shape_detail;

// Cluster c's goals: moved to directly, or written to the goal scratch of an overlapping cluster.
void match_cluster(const ParticleView& p, ShapeClusters& s, std::size_t c) {
  const float beta = s.linear_blend[c];
  ClusterFit fit;
  if (!fit_cluster(p, s, c, beta > 0.0f, fit)) return;  // nothing movable
  const Quat rot = closest_rotation_double(fit.apq, to_quat(s.rotation[c]));
  s.rotation[c] = {float(rot.x), float(rot.y), float(rot.z), float(rot.w)};
  double t[9];
  to_matrix(rot, t);
  double linear[9];
  if (beta > 0.0f && linear_map(fit, linear))
    for (int k = 0; k < 9; ++k) t[k] = double(beta) * linear[k] + (1.0 - double(beta)) * t[k];
  const double* centre = fit.centre;
  const bool overlapping = s.overlapping[c] != 0;
  const double stiffness = s.stiffness[c];
  const RestShape rest(s, c);
  const std::uint32_t* particle = s.particle.data();
  const float* w = p.w;
  float *px = p.px, *py = p.py, *pz = p.pz;
  for (std::uint32_t k = s.start[c], end = s.start[c + 1]; k < end; ++k) {
    const std::uint32_t i = particle[k];
    if (!(w[i] > 0.0f)) continue;
    double q[3];
    rest.offset(k, q);
    double goal[3];
    for (int row = 0; row < 3; ++row)
      goal[row] = centre[row] + t[3 * row] * q[0] + t[3 * row + 1] * q[1] + t[3 * row + 2] * q[2];
    if (overlapping) {
      s.goal_x[k] = goal[0], s.goal_y[k] = goal[1], s.goal_z[k] = goal[2];
      continue;
    }
    float* pos[3] = {&px[i], &py[i], &pz[i]};
    for (int row = 0; row < 3; ++row) *pos[row] = float(*pos[row] + stiffness * (goal[row] - *pos[row]));
  }
}

// A particle of overlapping clusters moves toward the mean of its clusters' goals.
void move_shared_particle(const ParticleView& p, const ShapeClusters& s, std::size_t j) {
  const std::uint32_t i = s.shared_particle[j];
  const std::uint32_t begin = s.shared_start[j], end = s.shared_start[j + 1];
  if (!(p.w[i] > 0.0f) || begin == end) return;
  double sum[3] = {0.0, 0.0, 0.0};
  for (std::uint32_t m = begin; m < end; ++m) {
    const std::uint32_t k = s.shared_member[m];
    sum[0] += s.goal_x[k], sum[1] += s.goal_y[k], sum[2] += s.goal_z[k];
  }
  const double count = double(end - begin), stiffness = s.shared_stiffness[j];
  float* pos[3] = {&p.px[i], &p.py[i], &p.pz[i]};
  for (int row = 0; row < 3; ++row) *pos[row] = float(*pos[row] + stiffness * (sum[row] / count - *pos[row]));
}

}  // namespace

void ShapeClusters::begin_cluster(float cluster_stiffness) {
  if (start.empty()) start.push_back(0);
  stiffness.push_back(cluster_stiffness);
  linear_blend.push_back(0.0f);
  overlapping.push_back(0);
  plasticity.push_back({});
  rotation.push_back(kIdentityRotation);
  plastic.push_back(kIdentityMatrix);
}

void ShapeClusters::add_member(std::uint32_t store_index, float qx, float qy, float qz, float mass_share) {
  particle.push_back(store_index);
  rest_x.push_back(qx), rest_y.push_back(qy), rest_z.push_back(qz);
  share.push_back(mass_share);
}

void ShapeClusters::end_cluster() { start.push_back(std::uint32_t(particle.size())); }

void ShapeClusters::finish() {
  if (start.empty()) start.push_back(0);
  if (shared_start.empty()) shared_start.push_back(0);
  bool any_overlapping = false;
  for (std::uint8_t o : overlapping) any_overlapping = any_overlapping || o != 0;
  const std::size_t scratch = any_overlapping ? members() : 0;
  goal_x.assign(scratch, 0.0), goal_y.assign(scratch, 0.0), goal_z.assign(scratch, 0.0);
}

void ShapeClusters::remap(std::span<const std::uint32_t> new_index) {
  for (std::uint32_t& k : particle) k = new_index[k];
  for (std::uint32_t& k : shared_particle) k = new_index[k];
}

Quaternion closest_rotation(const double a[9], Quaternion guess) {
  const Quat q = closest_rotation_double(a, to_quat(guess));
  return {float(q.x), float(q.y), float(q.z), float(q.w)};
}

void solve_shape_matching(const ParticleView& p, ShapeClusters& clusters) {
  // One cluster per task: its sums run in member order on one thread, so the result does not
  // depend on the thread count. Overlapping clusters only write their members' goals here.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, clusters.clusters(), 1), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) match_cluster(p, clusters, c);
  });
  if (clusters.shared_particle.empty()) return;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, clusters.shared_particle.size(), 256), [&](const auto& r) {
    for (std::size_t j = r.begin(); j != r.end(); ++j) move_shared_particle(p, clusters, j);
  });
}

}  // namespace seiche::kernels
