// Isometric bending (isometric_bending.hpp has the model; Bergou et al. 2006), XPBD with
//   C = sqrt(sum_ij Q_ij x_i . x_j) = |v|,  v = sum_i k_i x_i  (Q = k k^T)
//   grad_i C = k_i v / |v|,  sum_i w_i |grad_i C|^2 = sum_i w_i k_i^2
// With zero compliance one step flattens a hinge exactly (v moves linearly along itself).
#include "seiche/kernels/isometric_bending.hpp"

#include <cmath>
#include <type_traits>

#include "colored_batches.hpp"

namespace seiche::kernels {

namespace {

using colored::MaskOf;
using colored::select;
using colored::V3;
using simd::Floats;

/// One XPBD step of hinge(s) at positions p[0..3] = x0..x3 with Q = k k^T: returns dlambda (0
/// where the hinge is skipped) and the corrections dp[i] = w_i grad_i C dlambda.
template <class T>
SEICHE_INLINE inline T isometric_step(const V3<T> p[4], const T w[4], const T k[4], const T& alpha,
                                      const T& lambda, V3<T> dp[4]) {
  const T zero(0.0f), one(1.0f);
  // v = sum_i k_i x_i = sum_{i >= 1} k_i (x_i - x0) (k sums to zero): no absolute positions.
  const V3<T> v = (p[1] - p[0]) * k[1] + (p[2] - p[0]) * k[2] + (p[3] - p[0]) * k[3];
  const T C2 = dot(v, v);
  const MaskOf<T> ok = (C2 > T(1e-18f)) & (w[0] + w[1] + w[2] + w[3] > zero);
  const T C = colored::vsqrt(select(ok, C2, one));
  // grad_i C = k_i v / C:  sum_i w_i |grad_i C|^2 = sum_i w_i k_i^2.
  const T sum_grad2 =
      w[0] * k[0] * k[0] + w[1] * k[1] * k[1] + w[2] * k[2] * k[2] + w[3] * k[3] * k[3];
  const T dlambda = select(ok, (simd::negate(C) - alpha * lambda) / select(ok, sum_grad2 + alpha, one), zero);
  const V3<T> n = v * (one / C);
  for (int i = 0; i < 4; ++i) dp[i] = n * (w[i] * k[i] * dlambda);
  return dlambda;
}

}  // namespace

void build_isometric_bending(std::span<const std::uint32_t> hinge_vertices,
                             std::span<const float> bend_compliance, const ParticleView& rest,
                             IsometricBending& out) {
  Hinges& h = out.hinges;
  const std::vector<std::uint32_t> source = build_hinges(hinge_vertices, rest, h);
  const std::size_t m = source.size();
  for (auto& column : out.q) column.assign(m, 0.0f);
  for (auto& column : out.k) column.assign(m, 0.0f);
  for (std::size_t k = 0; k < m; ++k) {
    h.compliance[k] = bend_compliance[source[k]];
    // Rest geometry in double: x0..x3 = a, b, c, d.
    const std::uint32_t v[4] = {h.a[k], h.b[k], h.c[k], h.d[k]};
    double x[4][3];
    for (int s = 0; s < 4; ++s)
      x[s][0] = rest.x[v[s]], x[s][1] = rest.y[v[s]], x[s][2] = rest.z[v[s]];
    double e[5][3];  // e0 = x1 - x0, e1 = x2 - x0, e2 = x3 - x0, e3 = x2 - x1, e4 = x3 - x1
    for (int i = 0; i < 3; ++i) {
      e[0][i] = x[1][i] - x[0][i], e[1][i] = x[2][i] - x[0][i], e[2][i] = x[3][i] - x[0][i];
      e[3][i] = x[2][i] - x[1][i], e[4][i] = x[3][i] - x[1][i];
    }
    auto dotd = [](const double* u, const double* v) {
      return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    };
    auto cross_norm = [](const double* u, const double* v) {
      const double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2],
                   cz = u[0] * v[1] - u[1] * v[0];
      return std::sqrt(cx * cx + cy * cy + cz * cz);
    };
    const double e2 = dotd(e[0], e[0]);
    const double n1 = cross_norm(e[0], e[1]), n2 = cross_norm(e[0], e[2]);  // 2 A1, 2 A2
    const double min_wing = double(kHingeMinWing) * e2 * e2;
    if (!(e2 > kHingeMinEdge2) || !(n1 * n1 > min_wing) || !(n2 * n2 > min_wing))
      continue;  // Q = 0
    // cot(u, v) = u.v / |u x v|; |e1 x e0| = |e3 x e0| = 2 A1, |e2 x e0| = |e4 x e0| = 2 A2.
    const double c01 = dotd(e[0], e[1]) / n1, c02 = dotd(e[0], e[2]) / n2;
    const double c03 = -dotd(e[3], e[0]) / n1, c04 = -dotd(e[4], e[0]) / n2;
    const double K[4] = {c03 + c04, c01 + c02, -c01 - c03, -c02 - c04};
    const double scale = 3.0 / (0.5 * (n1 + n2));  // 3 / (A1 + A2)
    int entry = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j) out.q[entry++][k] = float(scale * K[i] * K[j]);
    // k = sqrt(scale) K, with k_0 rounded so that the four sum to zero in float as well.
    for (int i = 1; i < 4; ++i) out.k[i][k] = float(std::sqrt(scale) * K[i]);
    out.k[0][k] = -(out.k[1][k] + out.k[2][k] + out.k[3][k]);
  }
}

void solve_isometric_bending(const PackedPositions& packed, IsometricBending& b, float dt,
                             Multipliers start) {
  const float inv_dt2 = 1.0f / (dt * dt);
  Hinges& h = b.hinges;
  const float* const compliance = h.compliance.data();
  float* const lambda = h.lambda.data();
  const std::array<const float*, 4> k_columns = {nullptr, b.k[1].data(), b.k[2].data(),
                                                 b.k[3].data()};
  const bool restart = start == Multipliers::Restart;
  colored::solve_colored<4>(
      packed.by_index(), h.color_start, {h.a.data(), h.b.data(), h.c.data(), h.d.data()},
      [=](const colored::Batch& batch, const V3<Floats> x[4], const Floats w[4], V3<Floats> dp[4]) {
        const Floats alpha = batch.load(compliance) * Floats(inv_dt2);
        const Floats l = restart ? Floats(0.0f) : batch.load(lambda);
        // k_0 as the build stores it, -(k_1 + k_2 + k_3) in float (the same bits): one column
        // less to stream, a tenth of a hinge's bytes.
        const Floats k1 = batch.load(k_columns[1]), k2 = batch.load(k_columns[2]),
                     k3 = batch.load(k_columns[3]);
        const Floats k[4] = {simd::negate(k1 + k2 + k3), k1, k2, k3};
        const Floats dlambda = isometric_step(x, w, k, alpha, l, dp);
        batch.store(lambda, l + dlambda);
      });
}

void solve_isometric_bending(const ParticleView& p, IsometricBending& b, float dt) {
  const Hinges& h = b.hinges;
  colored::solve_packed(p, {h.a, h.b, h.c, h.d}, [&](const PackedPositions& packed) {
    solve_isometric_bending(packed, b, dt, Multipliers::Accumulate);
  });
}

}  // namespace seiche::kernels
