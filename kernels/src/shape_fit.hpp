// What shape matching and plastic flow share (internal to the kernels): 3 x 3 and quaternion
// algebra in double, and the fit of one cluster to the predicted positions:
//   c = sum m_i p_i / M,  Apq = sum m_i (p_i - c) q_i^T,  Mqq = sum m_i q_i q_i^T
// with m_i = share_i / w_i (1 / w_i outside overlapping clusters) and q_i the rest offset (Sp q_i
// for a plastic cluster). Each sum runs in member order. Hand-written instead of Eigen: the
// kernel layer does not depend on Eigen, and whether a library picks a SIMD path for a 3 x 3
// product would be one more thing that could make the bits differ between builds. Only
// + - * / sqrt: the same bits on every machine.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "seiche/kernels/shape_matching.hpp"

namespace seiche::kernels::shape_detail {

struct Quat {
  double x, y, z, w;
};

/// The rotation closest to a (row-major), by the iteration of Müller et al. 2016 from q.
Quat closest_rotation_double(const double a[9], Quat q);

inline Quat to_quat(const Quaternion& q) { return {q[0], q[1], q[2], q[3]}; }

/// The rotation matrix of a unit quaternion, row-major.
inline void to_matrix(const Quat& q, double r[9]) {
  const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
  const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  r[0] = 1.0 - 2.0 * (yy + zz), r[1] = 2.0 * (xy - wz), r[2] = 2.0 * (xz + wy);
  r[3] = 2.0 * (xy + wz), r[4] = 1.0 - 2.0 * (xx + zz), r[5] = 2.0 * (yz - wx);
  r[6] = 2.0 * (xz - wy), r[7] = 2.0 * (yz + wx), r[8] = 1.0 - 2.0 * (xx + yy);
}

/// out = a b
inline void multiply(const double a[9], const double b[9], double out[9]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

inline double determinant(const double m[9]) {
  return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

inline bool all_finite(const double m[9]) {
  for (int k = 0; k < 9; ++k)
    if (!std::isfinite(m[k])) return false;
  return true;
}

/// The inverse of the symmetric positive semi-definite moment m; false (and out untouched) where
/// m is singular for the purpose: det below 1e-9 of (trace / 3)^3 (a flat, linear or coincident
/// cluster), or not finite.
inline bool invert_moment(const double m[9], double out[9]) {
  const double det = determinant(m);
  const double mean = (m[0] + m[4] + m[8]) / 3.0;
  if (!(mean > 0.0) || !(det > 1e-9 * mean * mean * mean) || !std::isfinite(det)) return false;
  const double inv[9] = {(m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det,
                         (m[1] * m[5] - m[2] * m[4]) / det, (m[5] * m[6] - m[3] * m[8]) / det,
                         (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det,
                         (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det,
                         (m[0] * m[4] - m[1] * m[3]) / det};
  if (!all_finite(inv)) return false;
  for (int k = 0; k < 9; ++k) out[k] = inv[k];
  return true;
}

/// d^(1/3) for a finite d > 0 with + - * / only (no libm: the same bits everywhere): scaled by
/// powers of 8 into [1, 8), then Newton's iteration from 1.5, which has converged after 8 steps.
inline double cube_root(double d) {
  double scale = 1.0;
  while (d >= 8.0) d *= 0.125, scale *= 2.0;
  while (d < 1.0) d *= 8.0, scale *= 0.5;
  double x = 1.5;
  for (int step = 0; step < 8; ++step) x -= (x * x * x - d) / (3.0 * x * x);
  return x * scale;
}

/// The rest offsets of one cluster's members: q, or Sp q for a plastic cluster (read once per
/// cluster, so that the member loops do not test the cluster's settings per member).
struct RestShape {
  const float *x, *y, *z;
  const double* plastic;  ///< Sp, row-major; null for an elastic cluster

  RestShape(const ShapeClusters& s, std::size_t c)
      : x(s.rest_x.data()), y(s.rest_y.data()), z(s.rest_z.data()),
        plastic(s.plasticity[c].creep > 0.0f ? s.plastic[c].data() : nullptr) {}

  void offset(std::uint32_t k, double q[3]) const {
    q[0] = x[k], q[1] = y[k], q[2] = z[k];
    if (!plastic) return;
    const double q0[3] = {q[0], q[1], q[2]};
    for (int row = 0; row < 3; ++row)
      q[row] = plastic[3 * row] * q0[0] + plastic[3 * row + 1] * q0[1] + plastic[3 * row + 2] * q0[2];
  }
};

struct ClusterFit {
  double mass = 0.0;
  double centre[3] = {0.0, 0.0, 0.0};
  double apq[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  double mqq[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};  ///< only with_moment
};

// The centre of mass and Apq of cluster c: the rigid solve's hot loops, on raw pointers with
// the sums in registers, compiled per case so that a cluster that does not overlap (its members
// weigh their whole mass: m = 1 / w) and is elastic (no Sp) loads and tests nothing per member
// beyond what the rigid goal needs.
template <bool kShared, bool kPlastic>
bool rigid_sums(const ParticleView& p, const ShapeClusters& s, std::size_t c, ClusterFit& f) {
  const std::uint32_t begin = s.start[c], end = s.start[c + 1];
  const std::uint32_t* particle = s.particle.data();
  const float* share = s.share.data();
  const float *w = p.w, *px = p.px, *py = p.py, *pz = p.pz;
  const float *rx = s.rest_x.data(), *ry = s.rest_y.data(), *rz = s.rest_z.data();
  const double* sp = s.plastic[c].data();
  auto weight = [&](std::uint32_t k, std::uint32_t i) {
    if constexpr (kShared) return double(share[k]) / double(w[i]);
    else return 1.0 / double(w[i]);
  };
  double mass = 0.0, centre[3] = {0.0, 0.0, 0.0};
  for (std::uint32_t k = begin; k < end; ++k) {
    const std::uint32_t i = particle[k];
    if (!(w[i] > 0.0f)) continue;  // pinned: weighs nothing here
    const double m = weight(k, i);
    mass += m;
    centre[0] += m * px[i], centre[1] += m * py[i], centre[2] += m * pz[i];
  }
  if (!(mass > 0.0)) return false;
  for (double& v : centre) v /= mass;
  double apq[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (std::uint32_t k = begin; k < end; ++k) {
    const std::uint32_t i = particle[k];
    if (!(w[i] > 0.0f)) continue;
    const double m = weight(k, i);
    const double d[3] = {m * (px[i] - centre[0]), m * (py[i] - centre[1]), m * (pz[i] - centre[2])};
    double q[3] = {rx[k], ry[k], rz[k]};
    if constexpr (kPlastic) {
      const double q0[3] = {q[0], q[1], q[2]};
      for (int row = 0; row < 3; ++row)
        q[row] = sp[3 * row] * q0[0] + sp[3 * row + 1] * q0[1] + sp[3 * row + 2] * q0[2];
    }
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) apq[3 * row + col] += d[row] * q[col];
  }
  f.mass = mass;
  for (int a = 0; a < 3; ++a) f.centre[a] = centre[a];
  for (int k = 0; k < 9; ++k) f.apq[k] = apq[k];
  return true;
}

/// The fit of cluster c; false where no member is movable (all pinned).
inline bool fit_cluster(const ParticleView& p, const ShapeClusters& s, std::size_t c, bool with_moment,
                        ClusterFit& f) {
  const bool shared = s.overlapping[c] != 0, plastic = s.plasticity[c].creep > 0.0f;
  const bool movable = shared ? (plastic ? rigid_sums<true, true>(p, s, c, f) : rigid_sums<true, false>(p, s, c, f))
                              : (plastic ? rigid_sums<false, true>(p, s, c, f) : rigid_sums<false, false>(p, s, c, f));
  if (!movable || !with_moment) return movable;  // Mqq only where asked: the rigid solve does not pay for it
  const RestShape rest(s, c);
  for (std::uint32_t k = s.start[c]; k < s.start[c + 1]; ++k) {
    const std::uint32_t i = s.particle[k];
    if (!(p.w[i] > 0.0f)) continue;
    const double m = shared ? double(s.share[k]) / double(p.w[i]) : 1.0 / double(p.w[i]);
    double q[3];
    rest.offset(k, q);
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) f.mqq[3 * row + col] += m * q[row] * q[col];
  }
  return true;
}

/// A cluster whose volume changed by more than this factor (either way) is crushed or torn
/// (a contact squashed it flat): its linear fit says nothing, and scaling it back to its volume
/// would throw the goals far out. Müller 2005 leaves this open.
inline constexpr double kMaxVolumeChange = 8.0;

/// The best linear map from the rest shape to now, A = Apq Mqq^-1 with det A = 1; false where it
/// is undefined (see shape_matching.hpp).
inline bool linear_map(const ClusterFit& f, double a[9]) {
  double inv[9];
  if (!invert_moment(f.mqq, inv)) return false;
  multiply(f.apq, inv, a);
  const double det = determinant(a);
  if (!(det > 1.0 / kMaxVolumeChange) || !(det < kMaxVolumeChange)) return false;
  const double scale = 1.0 / cube_root(det);
  for (int k = 0; k < 9; ++k) a[k] *= scale;
  return all_finite(a);
}

}  // namespace seiche::kernels::shape_detail
