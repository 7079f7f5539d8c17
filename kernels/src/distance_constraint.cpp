#include "seiche/kernels/distance_constraint.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

namespace seiche::kernels {

std::vector<std::uint32_t> color_distance_constraints(std::span<const std::uint32_t> i,
                                                      std::span<const std::uint32_t> j,
                                                      std::span<const float> rest_length,
                                                      std::span<const float> compliance,
                                                      std::size_t particle_count,
                                                      DistanceConstraints& out) {
  const std::size_t m = i.size();
  // Greedy: each constraint takes the lowest color that neither endpoint uses yet. Colors in
  // use per particle are kept as a growing list of 64-bit masks.
  std::vector<std::vector<std::uint64_t>> used(particle_count);
  std::vector<std::uint32_t> color(m);
  std::uint32_t num_colors = 0;
  for (std::size_t c = 0; c < m; ++c) {
    auto& ui = used[i[c]];
    auto& uj = used[j[c]];
    std::uint32_t k = 0;
    for (;; ++k) {
      const std::size_t word = k / 64;
      const std::uint64_t bit = std::uint64_t(1) << (k % 64);
      const bool in_i = word < ui.size() && (ui[word] & bit);
      const bool in_j = word < uj.size() && (uj[word] & bit);
      if (!in_i && !in_j) break;
    }
    const std::size_t word = k / 64;
    const std::uint64_t bit = std::uint64_t(1) << (k % 64);
    if (ui.size() <= word) ui.resize(word + 1, 0);
    if (uj.size() <= word) uj.resize(word + 1, 0);
    ui[word] |= bit;
    uj[word] |= bit;
    color[c] = k;
    num_colors = std::max(num_colors, k + 1);
  }

  // Counting sort by color, stable.
  out.color_start.assign(num_colors + 1, 0);
  for (std::size_t c = 0; c < m; ++c) ++out.color_start[color[c] + 1];
  for (std::uint32_t k = 0; k < num_colors; ++k) out.color_start[k + 1] += out.color_start[k];
  std::vector<std::uint32_t> source(m);
  std::vector<std::uint32_t> cursor(out.color_start.begin(), out.color_start.end() - 1);
  for (std::size_t c = 0; c < m; ++c) source[cursor[color[c]]++] = std::uint32_t(c);

  out.i.resize(m);
  out.j.resize(m);
  out.rest_length.resize(m);
  out.compliance.resize(m);
  out.lambda.assign(m, 0.0f);
  for (std::size_t k = 0; k < m; ++k) {
    out.i[k] = i[source[k]];
    out.j[k] = j[source[k]];
    out.rest_length[k] = rest_length[source[k]];
    out.compliance[k] = compliance[source[k]];
  }
  return source;
}

void solve_distance_constraints(const ParticleView& p, DistanceConstraints& c, float dt) {
  const float inv_dt2 = 1.0f / (dt * dt);
  for (std::size_t color = 0; color + 1 < c.color_start.size(); ++color) {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(c.color_start[color], c.color_start[color + 1], 512),
        [&](const auto& r) {
          for (std::size_t k = r.begin(); k != r.end(); ++k) {
            const std::uint32_t a = c.i[k], b = c.j[k];
            const float wa = p.w[a], wb = p.w[b];
            const float alpha = c.compliance[k] * inv_dt2;
            const float denom = wa + wb + alpha;
            if (denom <= 0.0f) continue;  // both pinned and rigid: nothing can move
            const float dx = p.px[a] - p.px[b], dy = p.py[a] - p.py[b], dz = p.pz[a] - p.pz[b];
            const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
            if (len <= 1e-9f) continue;  // coincident: no direction
            const float C = len - c.rest_length[k];
            const float dlambda = (-C - alpha * c.lambda[k]) / denom;
            c.lambda[k] += dlambda;
            const float s = dlambda / len;  // dlambda * n = s * d
            p.px[a] += wa * s * dx;
            p.py[a] += wa * s * dy;
            p.pz[a] += wa * s * dz;
            p.px[b] -= wb * s * dx;
            p.py[b] -= wb * s * dy;
            p.pz[b] -= wb * s * dz;
          }
        });
  }
}

DistanceError distance_constraint_error(const ParticleView& p, const DistanceConstraints& c) {
  // Serial: constraint counts of raw constraints are small, and a serial sum is deterministic.
  DistanceError e;
  const std::size_t m = c.size();
  if (m == 0) return e;
  double sum = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    const std::uint32_t a = c.i[k], b = c.j[k];
    const double dx = double(p.x[a]) - p.x[b], dy = double(p.y[a]) - p.y[b],
                 dz = double(p.z[a]) - p.z[b];
    const double C = std::abs(std::sqrt(dx * dx + dy * dy + dz * dz) - c.rest_length[k]);
    const double rel = c.rest_length[k] > 0.0f ? C / c.rest_length[k] : C;
    sum += rel;
    e.max = std::max(e.max, rel);
  }
  e.mean = sum / double(m);
  return e;
}

}  // namespace seiche::kernels
