// Hinges (hinges.hpp): the signed dihedral angle
//   theta = atan2((n1 x n2) . e, n1 . n2),  n1 = (b - a) x (c - a),  n2 = (a - b) x (d - b),
//   e = (b - a) / |b - a|
// (hinge_angle.hpp computes it), the remapping of their indices when the store is reordered, and
// the bending error metric.
#include "seiche/kernels/hinges.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <xsimd/xsimd.hpp>

#include "hinge_angle.hpp"
#include "seiche/kernels/blocked_reduce.hpp"
#include "seiche/kernels/graph_coloring.hpp"
#include "seiche/simd/batch.hpp"

namespace seiche::kernels {

namespace {

template <class T>
T signed_angle(const T pa[3], const T pb[3], const T pc[3], const T pd[3]) {
  const colored::V3<T> p[4] = {
      {pa[0], pa[1], pa[2]}, {pb[0], pb[1], pb[2]}, {pc[0], pc[1], pc[2]}, {pd[0], pd[1], pd[2]}};
  const HingeFrame<T> h(p);
  if (!has_angle(h)) return T(0);
  return hinge_angle(h, std::sqrt(h.e2), [](const T& y, const T& x) { return std::atan2(y, x); });
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
// hinge, double precision, hinge_angle.hpp's formula with a select for the degenerate case;
// xsimd's atan2 agrees with the C library's to an ulp or two), then |theta - rest| and its sum in
// hinge order, in fixed blocks (blocked_reduce.hpp). The scalar loop called atan2 hinge by hinge:
// at 100 x 100 the whole metrics pass went from 1.16 to 0.81 ms (docs/performance.md, cloth). The
// batches are simd::Arch256's, AVX2 also in an AVX-512 build: xsimd's atan2 evaluates its
// polynomial with xsimd's fma, which is fused on AVX2 and not on AVX-512, so the report would
// otherwise differ between the two builds.
namespace {

using Doubles = xsimd::batch<double, seiche::simd::Arch256>;
constexpr std::size_t kDoubleLanes = Doubles::size;

Doubles signed_angles(const colored::V3<Doubles> p[4]) {
  const HingeFrame<Doubles> h(p);
  const Doubles theta = hinge_angle(h, xsimd::sqrt(h.e2), [](const Doubles& y, const Doubles& x) {
    return xsimd::atan2(y, x);
  });
  return xsimd::select(has_angle(h), theta, Doubles(0.0));
}

}  // namespace

BendingError bending_error(const ParticleView& p, const Hinges& h) {
  BendingError out;
  const std::size_t m = h.size();
  if (m == 0) return out;
  struct Sum {
    double sum = 0.0, max = 0.0;
  };
  const Sum total = blocked_reduce(
      m, Sum{},
      [&](std::size_t begin, std::size_t end) {
        // In locals: signed_angles is a call, after which anything reached through the
        // captures would be loaded again.
        const std::uint32_t* const vertex[4] = {h.a.data(), h.b.data(), h.c.data(), h.d.data()};
        const float* const rest_angle = h.rest_angle.data();
        const float *const x = p.x, *const y = p.y, *const z = p.z;
        Sum s;
        for (std::size_t k0 = begin; k0 < end; k0 += kDoubleLanes) {
          const std::size_t active = std::min(kDoubleLanes, end - k0);
          // Lane l: hinge k0 + l (padding lanes repeat the last one and are not counted).
          alignas(64) double q[4][3][kDoubleLanes];
          for (std::size_t l = 0; l < kDoubleLanes; ++l) {
            const std::size_t k = k0 + std::min(l, active - 1);
            for (int v = 0; v < 4; ++v) {
              const std::uint32_t i = vertex[v][k];
              q[v][0][l] = x[i], q[v][1][l] = y[i], q[v][2][l] = z[i];
            }
          }
          const auto at = [&](int v) -> colored::V3<Doubles> {
            return {Doubles::load_aligned(q[v][0]), Doubles::load_aligned(q[v][1]),
                    Doubles::load_aligned(q[v][2])};
          };
          const colored::V3<Doubles> pos[4] = {at(0), at(1), at(2), at(3)};
          alignas(64) double theta[kDoubleLanes];
          signed_angles(pos).store_aligned(theta);
          for (std::size_t l = 0; l < active; ++l) {
            double err = std::abs(theta[l] - double(rest_angle[k0 + l]));
            if (err > std::numbers::pi) err = 2.0 * std::numbers::pi - err;  // wrap into [0, pi]
            s.sum += err;
            s.max = std::max(s.max, err);
          }
        }
        return s;
      },
      [](Sum& acc, const Sum& s) { acc.sum += s.sum, acc.max = std::max(acc.max, s.max); });
  out.mean = total.sum / double(m);
  out.max = total.max;
  return out;
}

}  // namespace seiche::kernels
