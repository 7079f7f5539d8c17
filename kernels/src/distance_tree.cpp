// Exact projection of a forest of distance constraints (distance_tree.hpp has the math). Per
// tree, sweeps over its positions in a scratch record each:
//   forward   gather x, the parent edge's n and b, K = M I + geometric stiffness, r = 0
//   backward  (leaves to root) invert K, eliminate the vertex into its parent: d, s
//   forward   dlambda and dx from the parent's dx, the merit's parts (not applied yet)
//   forward   (once per trial step, usually once) the merit's penalty at x + beta dx
//   forward   write p and lambda, scaled by the accepted beta
// Trees are independent (disjoint particles and edges): they run in parallel, each serially.
#include "seiche/kernels/distance_tree.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace seiche::kernels {

namespace {

// Scratch record of a position (kStride floats). K: 3 x 3 as xx xy xz yy yz zz, then
// K^-1, then x0 (0..2) and the trial position y (3..5) of the line search; r, then dx; n of the
// parent edge; x during the first sweep, then the parent edge's 1 / d, s and dlambda; b of the
// parent edge.
constexpr std::size_t kStride = 16;
enum : std::size_t { kK = 0, kX0 = 0, kY = 3, kR = 6, kN = 9, kX = 12, kInvD = 12, kS = 13, kDl = 14, kB = 15 };
constexpr float kMinLength = 1e-9f;
// The line search (distance_tree.hpp): at most kHalvings halvings of the step, and a step must
// realize kArmijo of the merit's first-order decrease.
constexpr int kHalvings = 4;
constexpr double kArmijo = 0.1;

// In-place inverse of a symmetric positive definite 3 x 3 matrix (cofactors / determinant). K
// is M I plus positive semidefinite terms with M > 0, so det >= M^3 > 0; guarded all the same.
inline void invert_spd(float* k) {
  const float a = k[0], b = k[1], c = k[2], d = k[3], e = k[4], f = k[5];
  const float c00 = d * f - e * e, c01 = c * e - b * f, c02 = b * e - c * d;
  const float c11 = a * f - c * c, c12 = b * c - a * e, c22 = a * d - b * b;
  const float det = a * c00 + b * c01 + c * c02;
  const float inv = det > 0.0f ? 1.0f / det : 0.0f;
  k[0] = c00 * inv, k[1] = c01 * inv, k[2] = c02 * inv;
  k[3] = c11 * inv, k[4] = c12 * inv, k[5] = c22 * inv;
}

inline void mul_sym(const float* k, const float* v, float* out) {
  out[0] = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
  out[1] = k[1] * v[0] + k[3] * v[1] + k[4] * v[2];
  out[2] = k[2] * v[0] + k[4] * v[1] + k[5] * v[2];
}

// k (I - n n^T) added to the symmetric K.
inline void add_transverse(float* K, float k, const float* n) {
  K[0] += k - k * n[0] * n[0], K[1] -= k * n[0] * n[1], K[2] -= k * n[0] * n[2];
  K[3] += k - k * n[1] * n[1], K[4] -= k * n[1] * n[2], K[5] += k - k * n[2] * n[2];
}

// The penalty part of the merit at step length beta, the sum over the tree's edges of
//   |dlambda_e| |C_e(x0 + beta dx) + alpha~_e (lambda_e + beta dlambda_e)|,
// in position order, in double. Leaves y = x0 + beta dx in each record.
double merit_penalty(const DistanceConstraints& c, DistanceForest& f, std::size_t begin, std::size_t end,
                     float beta, float inv_dt2) {
  float* const s = f.scratch.data();
  double sum = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    float* v = s + i * kStride;
    for (std::size_t a = 0; a < 3; ++a) v[kY + a] = v[kX0 + a] + beta * v[kR + a];
    if (f.parent[i] == DistanceForest::kRoot || v[kDl] == 0.0f) continue;
    const float* q = s + std::size_t(f.parent[i]) * kStride;
    const float dx = v[kY] - q[kY], dy = v[kY + 1] - q[kY + 1], dz = v[kY + 2] - q[kY + 2];
    const std::uint32_t e = f.edge[i];
    const float residual = std::sqrt(dx * dx + dy * dy + dz * dz) - c.rest_length[e] +
                           c.compliance[e] * inv_dt2 * (c.lambda[e] + beta * v[kDl]);
    sum += double(std::abs(v[kDl])) * double(std::abs(residual));
  }
  return sum;
}

void solve_tree(const ParticleView& p, DistanceConstraints& c, DistanceForest& f, std::size_t begin,
                std::size_t end, float inv_dt2, const float* tension) {
  float* const s = f.scratch.data();
  const std::uint32_t* const parent = f.parent.data();
  const std::uint32_t* const edge = f.edge.data();
  const std::uint32_t* const particle = f.particle.data();

  // Forward: x, n and b of the parent edge, K = M I + geometric stiffness, r = 0.
  for (std::size_t i = begin; i < end; ++i) {
    float* v = s + i * kStride;
    const std::uint32_t a = particle[i];
    const float w = p.w[a];
    const float m = w > 0.0f ? 1.0f / w : 0.0f;
    v[0] = m, v[1] = 0.0f, v[2] = 0.0f, v[3] = m, v[4] = 0.0f, v[5] = m;
    v[kR] = v[kR + 1] = v[kR + 2] = 0.0f;
    v[kX] = p.px[a], v[kX + 1] = p.py[a], v[kX + 2] = p.pz[a];
    float* n = v + kN;
    n[0] = n[1] = n[2] = 0.0f;
    v[kB] = 0.0f;
    if (parent[i] == DistanceForest::kRoot) continue;
    float* q = s + std::size_t(parent[i]) * kStride;
    const float dx = v[kX] - q[kX], dy = v[kX + 1] - q[kX + 1], dz = v[kX + 2] - q[kX + 2];
    const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(len > kMinLength)) continue;  // coincident ends: no direction, the edge is skipped
    const float inv_len = 1.0f / len;
    n[0] = dx * inv_len, n[1] = dy * inv_len, n[2] = dz * inv_len;
    const std::uint32_t e = edge[i];
    v[kB] = -(len - c.rest_length[e]) - c.compliance[e] * inv_dt2 * c.lambda[e];
    const float t = tension ? -tension[e] : 0.0f;
    if (t > 0.0f) {
      // Capped at gamma times the lighter free end's mass.
      const float wq = p.w[particle[parent[i]]];
      const float lighter = std::min(m > 0.0f ? m : INFINITY, wq > 0.0f ? 1.0f / wq : INFINITY);
      const float k = std::isfinite(lighter) ? std::min(t * inv_len, kGeometricStiffnessCap * lighter) : 0.0f;
      add_transverse(v + kK, k, n);
      add_transverse(q + kK, k, n);
    }
  }

  // Backward: eliminate each vertex into its parent.
  for (std::size_t i = end; i-- > begin;) {
    float* v = s + i * kStride;
    const bool free = p.w[particle[i]] > 0.0f;
    if (free) invert_spd(v + kK);
    v[kInvD] = 0.0f, v[kS] = 0.0f, v[kDl] = 0.0f;
    if (parent[i] == DistanceForest::kRoot) continue;
    const float* n = v + kN;
    float u[3] = {0.0f, 0.0f, 0.0f};
    if (free) mul_sym(v + kK, n, u);
    const float d = n[0] * u[0] + n[1] * u[1] + n[2] * u[2] + c.compliance[edge[i]] * inv_dt2;
    // Skipped (d = 0): coincident ends (n = 0), or a rigid edge to a fixed vertex.
    if (!(d > 0.0f)) continue;
    const float inv_d = 1.0f / d;
    const float se = (v[kB] - (u[0] * v[kR] + u[1] * v[kR + 1] + u[2] * v[kR + 2])) * inv_d;
    v[kInvD] = inv_d, v[kS] = se;
    float* q = s + std::size_t(parent[i]) * kStride;
    const float m0 = n[0] * inv_d, m1 = n[1] * inv_d, m2 = n[2] * inv_d;
    q[0] += m0 * n[0], q[1] += m0 * n[1], q[2] += m0 * n[2];
    q[3] += m1 * n[1], q[4] += m1 * n[2], q[5] += m2 * n[2];
    q[kR] -= n[0] * se, q[kR + 1] -= n[1] * se, q[kR + 2] -= n[2] * se;
  }

  // Forward: the Newton step (dx, dlambda), not applied yet; K's slots take x0. Along the way
  // the merit's quadratic part and its first-order decrease.
  double quadratic = 0.0, decrease = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    float* v = s + i * kStride;
    const std::uint32_t a = particle[i];
    const float w = p.w[a];
    float rhs[3] = {v[kR], v[kR + 1], v[kR + 2]};
    if (parent[i] != DistanceForest::kRoot && v[kInvD] > 0.0f) {
      const float* q = s + std::size_t(parent[i]) * kStride;
      const float* n = v + kN;
      const float dlambda = v[kS] + (n[0] * q[kR] + n[1] * q[kR + 1] + n[2] * q[kR + 2]) * v[kInvD];
      v[kDl] = dlambda;
      rhs[0] += n[0] * dlambda, rhs[1] += n[1] * dlambda, rhs[2] += n[2] * dlambda;
      quadratic += double(c.compliance[edge[i]] * inv_dt2) * double(dlambda) * double(dlambda);
      decrease += double(std::abs(dlambda)) * double(std::abs(v[kB]));
    }
    float dx[3] = {0.0f, 0.0f, 0.0f};
    if (w > 0.0f) {
      mul_sym(v + kK, rhs, dx);
      quadratic += (double(dx[0]) * dx[0] + double(dx[1]) * dx[1] + double(dx[2]) * dx[2]) / double(w);
    }
    v[kR] = dx[0], v[kR + 1] = dx[1], v[kR + 2] = dx[2];
    v[kX0] = p.px[a], v[kX0 + 1] = p.py[a], v[kX0 + 2] = p.pz[a];
  }

  // Backtracking (distance_tree.hpp, safeguard 2): phi(0) = decrease = -phi'(0).
  if (!(decrease > 0.0)) return;  // the tree's edges are satisfied (b = 0) or cannot move
  float beta = 1.0f;
  for (int k = 0;; ++k) {
    const double phi = 0.5 * double(beta) * double(beta) * quadratic + merit_penalty(c, f, begin, end, beta, inv_dt2);
    if (phi <= decrease * (1.0 - kArmijo * double(beta))) break;
    if (k == kHalvings) return;  // no step along this direction helps: the tree stays as it is
    beta *= 0.5f;
  }
  // Apply beta (dx, dlambda).
  for (std::size_t i = begin; i < end; ++i) {
    const float* v = s + i * kStride;
    const std::uint32_t a = particle[i];
    if (parent[i] != DistanceForest::kRoot) c.lambda[edge[i]] += beta * v[kDl];
    if (p.w[a] > 0.0f) p.px[a] = v[kY], p.py[a] = v[kY + 1], p.pz[a] = v[kY + 2];
  }
}

}  // namespace

void DistanceForest::remap(std::span<const std::uint32_t> new_index) {
  for (std::uint32_t& k : particle) k = new_index[k];
}

DistanceForest make_distance_forest(std::span<const std::uint32_t> particle,
                                    std::span<const std::uint32_t> parent,
                                    std::span<const std::uint32_t> edge, std::size_t min_vertices) {
  const std::size_t n = particle.size();
  constexpr std::uint32_t kRoot = DistanceForest::kRoot;
  min_vertices = std::max<std::size_t>(min_vertices, 2);
  // Tree of each position (the position of its root) and the number of vertices of each root's tree.
  std::vector<std::uint32_t> root(n), vertices(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    root[i] = parent[i] == kRoot ? std::uint32_t(i) : root[parent[i]];
    ++vertices[root[i]];
  }
  // Trees in the order of their roots, positions in the given order inside each tree.
  std::vector<std::uint32_t> tree_of_root(n, kRoot), tree_size;
  for (std::size_t i = 0; i < n; ++i) {
    if (parent[i] != kRoot || vertices[i] < min_vertices) continue;
    tree_of_root[i] = std::uint32_t(tree_size.size());
    tree_size.push_back(std::uint32_t(vertices[i]));
  }
  DistanceForest f;
  f.tree_start.assign(tree_size.size() + 1, 0);
  for (std::size_t t = 0; t < tree_size.size(); ++t) f.tree_start[t + 1] = f.tree_start[t] + tree_size[t];
  const std::size_t kept = f.tree_start.back();
  f.particle.resize(kept), f.parent.resize(kept), f.edge.resize(kept);
  std::vector<std::uint32_t> cursor(f.tree_start.begin(), f.tree_start.end() - 1), position(n, kRoot);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t t = tree_of_root[root[i]];
    if (t == kRoot) continue;
    const std::uint32_t k = cursor[t]++;
    position[i] = k;
    f.particle[k] = particle[i];
    f.parent[k] = parent[i] == kRoot ? kRoot : position[parent[i]];
    f.edge[k] = parent[i] == kRoot ? 0u : edge[i];
  }
  f.scratch.resize(kept * kStride);
  return f;
}

void solve_distance_forest(const ParticleView& p, DistanceConstraints& c, DistanceForest& f, float dt,
                           const float* tension) {
  const std::size_t trees = f.trees();
  if (trees == 0) return;
  const float inv_dt2 = 1.0f / (dt * dt);
  f.scratch.resize(f.size() * kStride);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, trees, 1), [&](const auto& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t)
      solve_tree(p, c, f, f.tree_start[t], f.tree_start[t + 1], inv_dt2, tension);
  });
}

}  // namespace seiche::kernels
