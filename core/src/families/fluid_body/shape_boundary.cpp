// Shape particles as the fluid's boundary particles (the formulas are in shape_boundary.hpp).
#include "shape_boundary.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "families/fluid/fluid_ball_query.hpp"
#include "families/shape/shape_sites.hpp"
#include "seiche/phase.hpp"

namespace seiche::fluid_body {

namespace {

// psi of every site of one shape at rest: 1 / sum_k W(|q_b - q_k|) over its sites, the sites
// bucketed into cells of h (sorted by cell, then site order) so that each sum visits the 27
// cells around its site in a fixed order.
void add_rest_volumes(const std::vector<Vec3>& sites, const kernels::SphKernel& kernel, std::vector<double>& psi) {
  const std::size_t n = sites.size();
  if (n == 0) return;
  const double h = kernel.h;
  double lo[3] = {INFINITY, INFINITY, INFINITY};
  for (const Vec3& q : sites)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], double(q[a]));
  std::vector<std::array<std::int64_t, 3>> cell(n);
  for (std::size_t s = 0; s < n; ++s)
    for (int a = 0; a < 3; ++a) cell[s][a] = std::int64_t(std::floor((double(sites[s][a]) - lo[a]) / h));
  std::vector<std::uint32_t> order(n);
  for (std::size_t s = 0; s < n; ++s) order[s] = std::uint32_t(s);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return cell[a] < cell[b]; });
  const std::size_t first = psi.size();
  psi.resize(first + n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
    for (std::size_t s = range.begin(); s != range.end(); ++s) {
      double sum = 0.0;
      for (std::int64_t dz = -1; dz <= 1; ++dz)
        for (std::int64_t dy = -1; dy <= 1; ++dy)
          for (std::int64_t dx = -1; dx <= 1; ++dx) {
            const std::array<std::int64_t, 3> c{cell[s][0] + dx, cell[s][1] + dy, cell[s][2] + dz};
            auto at = std::lower_bound(order.begin(), order.end(), c,
                                       [&](std::uint32_t k, const std::array<std::int64_t, 3>& v) { return cell[k] < v; });
            for (; at != order.end() && cell[*at] == c; ++at) {
              const Vec3& q = sites[*at];
              const float rx = sites[s][0] - q[0], ry = sites[s][1] - q[1], rz = sites[s][2] - q[2];
              sum += double(kernel.poly6(rx * rx + ry * ry + rz * rz));
            }
          }
      psi[first + s] = sum > 0.0 ? 1.0 / sum : 0.0;  // b itself is in the sum: > 0 for h > 0
    }
  });
}

}  // namespace

ShapeBoundary::ShapeBoundary(const SceneDef& scene, std::int32_t first_id, double h) : first_id_(first_id) {
  const kernels::SphKernel kernel{float(h)};
  for (std::size_t c = 0; c < scene.shapes.size(); ++c)
    add_rest_volumes(shape_sites(scene.shapes[c], "shapes[" + std::to_string(c) + "]").position, kernel, psi_);
}

void ShapeBoundary::find_pairs(const ParticleStore& store, const Neighborhood& fluid) {
  shape_particle_.clear();
  const std::size_t fluid_count = fluid.count();
  for (std::size_t i = fluid_count; i < store.size(); ++i)
    if (phase_material(store.phase[i]) == Material::Shape) shape_particle_.push_back(std::uint32_t(i));
  const std::size_t m = shape_particle_.size();
  const float h = fluid.radius;
  const neighbor::CellGrid& grid = fluid.grid;
  // Calls visit(fluid j) for the fluid particles within h of shape particle i, in cell order.
  const auto visit_fluid = [&](std::uint32_t i, auto&& visit) {
    const float xi = store.px[i], yi = store.py[i], zi = store.pz[i];
    if (fluid_count == 0 || !std::isfinite(xi) || !std::isfinite(yi) || !std::isfinite(zi)) return;
    for_each_fluid_particle_within(grid, store, xi, yi, zi, h, visit);
  };
  // Shape-major: count, prefix sum, fill (each shape particle writes only its own range).
  shape_start_.assign(m + 1, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 64), [&](const auto& range) {
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      std::uint32_t count = 0;
      visit_fluid(shape_particle_[g], [&](std::uint32_t) { ++count; });
      shape_start_[g + 1] = count;
    }
  });
  for (std::size_t g = 0; g < m; ++g) shape_start_[g + 1] += shape_start_[g];
  const std::size_t pairs = shape_start_[m];
  pair_fluid_.resize(pairs);
  pair_shape_.resize(pairs);
  pair_psi_.resize(pairs);
  pair_gradient_.assign(3 * pairs, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 64), [&](const auto& range) {
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      const std::uint32_t i = shape_particle_[g];
      const double psi = volume(store.id[i]);
      std::uint32_t e = shape_start_[g];
      visit_fluid(i, [&](std::uint32_t j) { pair_fluid_[e] = j, pair_shape_[e] = i, pair_psi_[e] = psi, ++e; });
    }
  });
  // Fluid-major: a counting sort of the pairs by fluid particle, in pair order.
  fluid_start_.assign(fluid_count + 1, 0);
  for (std::uint32_t j : pair_fluid_) ++fluid_start_[j + 1];
  for (std::size_t i = 0; i < fluid_count; ++i) fluid_start_[i + 1] += fluid_start_[i];
  fluid_pair_.resize(pairs);
  std::vector<std::uint32_t> next(fluid_start_.begin(), fluid_start_.end() - 1);
  for (std::size_t e = 0; e < pairs; ++e) fluid_pair_[next[pair_fluid_[e]]++] = std::uint32_t(e);
}

void ShapeBoundary::gather(const ParticleStore& store, std::size_t i, double rest_density,
                           const kernels::SphKernel& kernel, double& density, double gradient[3]) {
  if (i + 1 >= fluid_start_.size()) return;
  const float xi = store.px[i], yi = store.py[i], zi = store.pz[i];
  for (std::uint32_t k = fluid_start_[i]; k < fluid_start_[i + 1]; ++k) {
    const std::uint32_t e = fluid_pair_[k];
    const std::uint32_t b = pair_shape_[e];
    const float rx = xi - store.px[b], ry = yi - store.py[b], rz = zi - store.pz[b];
    const float r2 = rx * rx + ry * ry + rz * rz;
    const double psi = pair_psi_[e];
    density += rest_density * psi * double(kernel.poly6(r2));
    const double g = psi * double(kernel.spiky_grad_over_r(r2));
    double* ge = &pair_gradient_[3 * std::size_t(e)];
    ge[0] = g * rx, ge[1] = g * ry, ge[2] = g * rz;
    gradient[0] += ge[0], gradient[1] += ge[1], gradient[2] += ge[2];
  }
}

void ShapeBoundary::solve(ParticleStore& store, std::size_t fluid_count, double mass) const {
  if (shape_particle_.empty()) return;
  float* px = store.px.data();
  float* py = store.py.data();
  float* pz = store.pz.data();
  const float* lambda = store.lambda.data();
  // The shape particles' reaction first: it reads the fluid's lambda, which the fluid's
  // correction below does not change.
  const std::size_t m = shape_particle_.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 64), [&](const auto& range) {
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      double sum[3] = {0.0, 0.0, 0.0};
      for (std::uint32_t e = shape_start_[g]; e < shape_start_[g + 1]; ++e) {
        const double lambda_i = lambda[pair_fluid_[e]];
        if (!(lambda_i < 0.0)) continue;
        const double* ge = &pair_gradient_[3 * std::size_t(e)];
        sum[0] += lambda_i * ge[0], sum[1] += lambda_i * ge[1], sum[2] += lambda_i * ge[2];
      }
      const std::uint32_t b = shape_particle_[g];
      const double scale = -mass * double(store.w[b]);
      px[b] += float(scale * sum[0]), py[b] += float(scale * sum[1]), pz[b] += float(scale * sum[2]);
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fluid_count, 4096), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      if (fluid_start_[i] == fluid_start_[i + 1]) continue;
      const double lambda_i = lambda[i];
      if (!(lambda_i < 0.0)) continue;
      double dp[3] = {0.0, 0.0, 0.0};
      for (std::uint32_t k = fluid_start_[i]; k < fluid_start_[i + 1]; ++k) {
        const double* ge = &pair_gradient_[3 * std::size_t(fluid_pair_[k])];
        dp[0] += ge[0], dp[1] += ge[1], dp[2] += ge[2];
      }
      px[i] += float(lambda_i * dp[0]), py[i] += float(lambda_i * dp[1]), pz[i] += float(lambda_i * dp[2]);
    }
  });
}

}  // namespace seiche::fluid_body
