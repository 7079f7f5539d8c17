// Hinges (hinges.hpp): the signed dihedral angle
//   theta = atan2((n1 x n2) . e, n1 . n2),  n1 = (b - a) x (c - a),  n2 = (a - b) x (d - b),
//   e = (b - a) / |b - a|,
// the remapping of their indices when the store is reordered, and the bending error metric.
#include "seiche/kernels/hinges.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <xsimd/xsimd.hpp>

#include "seiche/kernels/graph_coloring.hpp"
#include "seiche/simd/batch.hpp"

namespace seiche::kernels {

namespace {

template <class T>
T signed_angle(const T pa[3], const T pb[3], const T pc[3], const T pd[3]) {
  const T e[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
  const T ac[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
  const T bd[3] = {pd[0] - pb[0], pd[1] - pb[1], pd[2] - pb[2]};
  // n1 = e x ac; n2 = (a - b) x (d - b) = bd x e.
  const T n1[3] = {e[1] * ac[2] - e[2] * ac[1], e[2] * ac[0] - e[0] * ac[2],
                   e[0] * ac[1] - e[1] * ac[0]};
  const T n2[3] = {bd[1] * e[2] - bd[2] * e[1], bd[2] * e[0] - bd[0] * e[2],
                   bd[0] * e[1] - bd[1] * e[0]};
  const T e2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
  const T n1sq = n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2];
  const T n2sq = n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2];
  const T min_wing = T(kHingeMinWing) * e2 * e2;
  if (!(e2 > T(kHingeMinEdge2)) || !(n1sq > min_wing) || !(n2sq > min_wing)) return T(0);
  const T m[3] = {n1[1] * n2[2] - n1[2] * n2[1], n1[2] * n2[0] - n1[0] * n2[2],
                  n1[0] * n2[1] - n1[1] * n2[0]};
  const T sin_part = (m[0] * e[0] + m[1] * e[1] + m[2] * e[2]) / std::sqrt(e2);
  const T cos_part = n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2];
  return std::atan2(sin_part, cos_part);
}

}  // namespace

float dihedral_angle(const float pa[3], const float pb[3], const float pc[3], const float pd[3]) {
  return signed_angle(pa, pb, pc, pd);
}

double dihedral_angle(const double pa[3], const double pb[3], const double pc[3],
                      const double pd[3]) {
  return signed_angle(pa, pb, pc, pd);
}

void Hinges::remap(std::span<const std::uint32_t> new_index) {
  for (auto* v : {&a, &b, &c, &d})
    for (std::uint32_t& k : *v) k = new_index[k];
}

std::vector<std::uint32_t> build_hinges(std::span<const std::uint32_t> hinge_vertices,
                                        const ParticleView& rest, Hinges& out) {
  Coloring coloring = color_constraints(hinge_vertices, 4, rest.n);
  const std::size_t m = coloring.order.size();
  out.a.resize(m), out.b.resize(m), out.c.resize(m), out.d.resize(m);
  out.rest_angle.resize(m);
  out.compliance.assign(m, 0.0f);
  out.lambda.assign(m, 0.0f);
  out.color_start = std::move(coloring.color_start);
  for (std::size_t k = 0; k < m; ++k) {
    const std::uint32_t* v = hinge_vertices.data() + 4 * std::size_t(coloring.order[k]);
    out.a[k] = v[0], out.b[k] = v[1], out.c[k] = v[2], out.d[k] = v[3];
    double q[4][3];
    for (int s = 0; s < 4; ++s)
      q[s][0] = rest.x[v[s]], q[s][1] = rest.y[v[s]], q[s][2] = rest.z[v[s]];
    double theta = dihedral_angle(q[0], q[1], q[2], q[3]);
    if (theta <= -std::numbers::pi) theta = std::numbers::pi;  // (-pi, pi]
    out.rest_angle[k] = float(theta);
  }
  return std::move(coloring.order);
}

// The run report's bending error, every frame: the angles kDoubleLanes hinges at a time (lane =
// hinge, double precision, signed_angle's formula with a select for the degenerate case; xsimd's
// atan2 agrees with the C library's to an ulp or two), then |theta - rest| and its sum in hinge
// order. The scalar loop called atan2 hinge by hinge: at 100 x 100 the whole metrics pass went
// from 1.16 to 0.81 ms (docs/performance.md, cloth). The batches are simd::Arch256's, AVX2 also
// in an AVX-512 build: xsimd's atan2 evaluates its polynomial with xsimd's fma, which is fused on
// AVX2 and not on AVX-512, so the report would otherwise differ between the two builds.
namespace {

using Doubles = xsimd::batch<double, simd::Arch256>;
constexpr std::size_t kDoubleLanes = Doubles::size;

Doubles signed_angles(const Doubles pa[3], const Doubles pb[3], const Doubles pc[3],
                      const Doubles pd[3]) {
  const Doubles e[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
  const Doubles ac[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
  const Doubles bd[3] = {pd[0] - pb[0], pd[1] - pb[1], pd[2] - pb[2]};
  const Doubles n1[3] = {e[1] * ac[2] - e[2] * ac[1], e[2] * ac[0] - e[0] * ac[2],
                         e[0] * ac[1] - e[1] * ac[0]};
  const Doubles n2[3] = {bd[1] * e[2] - bd[2] * e[1], bd[2] * e[0] - bd[0] * e[2],
                         bd[0] * e[1] - bd[1] * e[0]};
  const Doubles e2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
  const Doubles n1sq = n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2];
  const Doubles n2sq = n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2];
  const Doubles min_wing = Doubles(double(kHingeMinWing)) * e2 * e2;
  const auto valid =
      (e2 > Doubles(double(kHingeMinEdge2))) && (n1sq > min_wing) && (n2sq > min_wing);
  const Doubles m[3] = {n1[1] * n2[2] - n1[2] * n2[1], n1[2] * n2[0] - n1[0] * n2[2],
                        n1[0] * n2[1] - n1[1] * n2[0]};
  const Doubles sin_part = (m[0] * e[0] + m[1] * e[1] + m[2] * e[2]) / xsimd::sqrt(e2);
  const Doubles cos_part = n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2];
  return xsimd::select(valid, xsimd::atan2(sin_part, cos_part), Doubles(0.0));
}

}  // namespace

BendingError bending_error(const ParticleView& p, const Hinges& h) {
  // Parallel over fixed blocks of hinges, each summed in order, the blocks combined in order:
  // the same bits with any thread count.
  BendingError out;
  const std::size_t m = h.size();
  if (m == 0) return out;
  constexpr std::size_t kBlock = 4096;
  const std::size_t blocks = (m + kBlock - 1) / kBlock;
  std::vector<double> sum(blocks, 0.0), max(blocks, 0.0);
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t blk) {
    const std::size_t end = std::min(m, (blk + 1) * kBlock);
    double s = 0.0, mx = 0.0;
    for (std::size_t k0 = blk * kBlock; k0 < end; k0 += kDoubleLanes) {
      const std::size_t active = std::min(kDoubleLanes, end - k0);
      // Lane l: hinge k0 + l (padding lanes repeat the last one and are not counted).
      alignas(64) double q[4][3][kDoubleLanes];
      const std::uint32_t* const vertex[4] = {h.a.data(), h.b.data(), h.c.data(), h.d.data()};
      for (std::size_t l = 0; l < kDoubleLanes; ++l) {
        const std::size_t k = k0 + std::min(l, active - 1);
        for (int v = 0; v < 4; ++v) {
          const std::uint32_t i = vertex[v][k];
          q[v][0][l] = p.x[i], q[v][1][l] = p.y[i], q[v][2][l] = p.z[i];
        }
      }
      Doubles pos[4][3];
      for (int v = 0; v < 4; ++v)
        for (int a = 0; a < 3; ++a) pos[v][a] = Doubles::load_aligned(q[v][a]);
      alignas(64) double theta[kDoubleLanes];
      signed_angles(pos[0], pos[1], pos[2], pos[3]).store_aligned(theta);
      for (std::size_t l = 0; l < active; ++l) {
        double err = std::abs(theta[l] - double(h.rest_angle[k0 + l]));
        if (err > std::numbers::pi) err = 2.0 * std::numbers::pi - err;  // wrap into [0, pi]
        s += err;
        mx = std::max(mx, err);
      }
    }
    sum[blk] = s, max[blk] = mx;
  });
  double total = 0.0;
  for (std::size_t blk = 0; blk < blocks; ++blk) {
    total += sum[blk];
    out.max = std::max(out.max, max[blk]);
  }
  out.mean = total / double(m);
  return out;
}

}  // namespace seiche::kernels
