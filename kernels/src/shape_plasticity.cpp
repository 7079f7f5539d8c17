// Plastic flow of shape-matched clusters: the steps of shape_plasticity.hpp.
#include "seiche/kernels/shape_plasticity.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

#include "shape_fit.hpp"

namespace seiche::kernels {

namespace {

using namespace shape_detail;

double frobenius(const double m[9]) {
  double sum = 0.0;
  for (int k = 0; k < 9; ++k) sum += m[k] * m[k];
  return std::sqrt(sum);
}

// S - I of cluster c, S = sym(R^T A); false where the linear map is undefined.
bool strain(const ParticleView& p, const ShapeClusters& s, std::size_t c, double d[9]) {
  ClusterFit fit;
  if (!fit_cluster(p, s, c, true, fit)) return false;
  double a[9];
  if (!linear_map(fit, a)) return false;
  double r[9];
  to_matrix(closest_rotation_double(fit.apq, to_quat(s.rotation[c])), r);
  const double rt[9] = {r[0], r[3], r[6], r[1], r[4], r[7], r[2], r[5], r[8]};
  double stretch[9];
  multiply(rt, a, stretch);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d[3 * i + j] = 0.5 * (stretch[3 * i + j] + stretch[3 * j + i]) - (i == j ? 1.0 : 0.0);
  return all_finite(d);
}

void flow(const ParticleView& p, ShapeClusters& s, std::size_t c, double dt) {
  const Plasticity& plastic = s.plasticity[c];
  if (!(plastic.creep > 0.0f)) return;
  double d[9];
  if (!strain(p, s, c, d) || !(frobenius(d) > double(plastic.yield))) return;
  double step[9];
  for (int k = 0; k < 9; ++k) step[k] = dt * double(plastic.creep) * d[k] + kIdentityMatrix[k];
  double sp[9];
  multiply(step, s.plastic[c].data(), sp);
  double e[9];
  for (int k = 0; k < 9; ++k) e[k] = sp[k] - kIdentityMatrix[k];
  const double length = frobenius(e);
  if (length > double(plastic.max_strain))
    for (int k = 0; k < 9; ++k) sp[k] = kIdentityMatrix[k] + double(plastic.max_strain) * e[k] / length;
  const double det = determinant(sp);
  if (!(det > 0.0) || !std::isfinite(det)) return;
  const double scale = 1.0 / cube_root(det);
  for (double& v : sp) v *= scale;
  if (!all_finite(sp)) return;
  for (int k = 0; k < 9; ++k) s.plastic[c][k] = sp[k];
}

}  // namespace

void update_shape_plasticity(const ParticleView& p, ShapeClusters& clusters, float dt) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, clusters.clusters(), 1), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) flow(p, clusters, c, dt);
  });
}

double shape_strain(const ParticleView& p, const ShapeClusters& clusters, std::size_t c) {
  double d[9];
  return strain(p, clusters, c, d) ? frobenius(d) : 0.0;
}

}  // namespace seiche::kernels
