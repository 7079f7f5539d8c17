// Dihedral-angle bending, XPBD (dihedral_bending.hpp has the model). For hinge (a, b, c, d),
// e = b - a, n1 = e x (c - a), n2 = (d - b) x e (the normals of hinges.hpp; theta and the
// degenerate test are hinge_angle.hpp's):
//   C = theta - theta0, wrapped into (-pi, pi]
//   grad_c = -|e| n1 / |n1|^2,   grad_d = -|e| n2 / |n2|^2       (a wing turns about the edge
//                                                                  by its displacement / height)
//   grad_a = (s_c - 1) grad_c + (s_d - 1) grad_d,  grad_b = -s_c grad_c - s_d grad_d,
//   s_c = (c - a).e / |e|^2,  s_d = (d - a).e / |e|^2            (where c, d project on the edge)
// (Bridson et al. 2003, sec. 4, in this file's orientation; the gradients sum to zero and are
// checked against finite differences in tests/cloth_kernel_tests.cpp).
// A hinge with a zero-length edge, a zero-area wing or only pinned vertices is skipped.
#include "seiche/kernels/dihedral_bending.hpp"

#include <cmath>
#include <numbers>
#include <type_traits>

#include "colored_batches.hpp"
#include "hinge_angle.hpp"

namespace seiche::kernels {

namespace {

using colored::MaskOf;
using colored::select;
using colored::V3;
using simd::Floats;

/// One XPBD step of hinge(s) at positions p[0..3] = a, b, c, d: returns dlambda (0 where the
/// hinge is skipped) and the position corrections dp[i] = w_i grad_i C dlambda (finite in every
/// lane, 0 where skipped).
template <class T>
SEICHE_INLINE inline T dihedral_step(const V3<T> p[4], const T w[4], const T& rest, const T& alpha,
                                     const T& lambda, V3<T> dp[4]) {
  const T zero(0.0f), one(1.0f), pi(std::numbers::pi_v<float>),
      minus_pi(-std::numbers::pi_v<float>), two_pi(2.0f * std::numbers::pi_v<float>);
  const HingeFrame<T> h(p);
  const MaskOf<T> ok = has_angle(h) & (w[0] + w[1] + w[2] + w[3] > zero);
  // Where the hinge is skipped, divide by 1 instead: every lane stays finite.
  const T e2_safe = select(ok, h.e2, one);
  const T len = colored::vsqrt(e2_safe);
  T C = hinge_angle(h, len, [](const T& y, const T& x) { return simd::atan2(y, x); }) - rest;
  C = select(C > pi, C - two_pi, C);
  C = select(C <= minus_pi, C + two_pi, C);

  const V3<T> gc = h.n1 * (simd::negate(len) / select(ok, h.n1sq, one));
  const V3<T> gd = h.n2 * (simd::negate(len) / select(ok, h.n2sq, one));
  const V3<T> ac = p[2] - p[0], ad = p[3] - p[0];
  const T sc = dot(ac, h.e) / e2_safe, sd = dot(ad, h.e) / e2_safe;
  const V3<T> ga = gc * (sc - one) + gd * (sd - one);
  const V3<T> gb = gc * simd::negate(sc) - gd * sd;
  const T denom =
      w[0] * dot(ga, ga) + w[1] * dot(gb, gb) + w[2] * dot(gc, gc) + w[3] * dot(gd, gd) + alpha;
  const T dlambda = select(ok, (simd::negate(C) - alpha * lambda) / select(ok, denom, one), zero);
  dp[0] = ga * (w[0] * dlambda);
  dp[1] = gb * (w[1] * dlambda);
  dp[2] = gc * (w[2] * dlambda);
  dp[3] = gd * (w[3] * dlambda);
  return dlambda;
}

}  // namespace

void build_dihedral_bending(std::span<const std::uint32_t> hinge_vertices,
                            std::span<const float> bend_compliance, const ParticleView& rest,
                            Hinges& out) {
  const std::vector<std::uint32_t> source = build_hinges(hinge_vertices, rest, out);
  for (std::size_t k = 0; k < source.size(); ++k) {
    // alpha_hinge = bend_compliance (A1 + A2) / (3 |e|^2), from the rest shape, in double.
    const std::uint32_t v[4] = {out.a[k], out.b[k], out.c[k], out.d[k]};
    double q[4][3];
    for (int s = 0; s < 4; ++s)
      q[s][0] = rest.x[v[s]], q[s][1] = rest.y[v[s]], q[s][2] = rest.z[v[s]];
    double e[3], ac[3], bd[3];
    for (int i = 0; i < 3; ++i)
      e[i] = q[1][i] - q[0][i], ac[i] = q[2][i] - q[0][i], bd[i] = q[3][i] - q[1][i];
    auto cross_norm = [](const double u[3], const double v[3]) {
      const double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2],
                   cz = u[0] * v[1] - u[1] * v[0];
      return std::sqrt(cx * cx + cy * cy + cz * cz);
    };
    const double e2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    const double n1 = cross_norm(e, ac), n2 = cross_norm(bd, e);  // 2 A1, 2 A2
    const double min_wing = double(kHingeMinWing) * e2 * e2;
    const bool degenerate =
        !(e2 > kHingeMinEdge2) || !(n1 * n1 > min_wing) || !(n2 * n2 > min_wing);
    const double scale = degenerate ? 1.0 / 3.0 : 0.5 * (n1 + n2) / (3.0 * e2);
    out.compliance[k] = float(double(bend_compliance[source[k]]) * scale);
  }
}

void solve_dihedral_bending(const PackedPositions& packed, Hinges& h, float dt, Multipliers start) {
  const float inv_dt2 = 1.0f / (dt * dt);
  const float* const compliance = h.compliance.data();
  const float* const rest_angle = h.rest_angle.data();
  float* const lambda = h.lambda.data();
  const bool restart = start == Multipliers::Restart;
  colored::solve_colored<4>(
      packed.by_index(), h.color_start, {h.a.data(), h.b.data(), h.c.data(), h.d.data()},
      [=](const colored::Batch& batch, const V3<Floats> x[4], const Floats w[4], V3<Floats> dp[4]) {
        const Floats alpha = batch.load(compliance) * Floats(inv_dt2);
        const Floats l = restart ? Floats(0.0f) : batch.load(lambda);
        const Floats dlambda = dihedral_step(x, w, batch.load(rest_angle), alpha, l, dp);
        batch.store(lambda, l + dlambda);
      });
}

void solve_dihedral_bending(const ParticleView& p, Hinges& h, float dt) {
  colored::solve_packed(p, {h.a, h.b, h.c, h.d}, [&](const PackedPositions& packed) {
    solve_dihedral_bending(packed, h, dt, Multipliers::Accumulate);
  });
}

}  // namespace seiche::kernels
