// XPBD distance constraints (distance_constraint.hpp has the math). Coloring: the greedy
// coloring of graph_coloring.hpp on the pairs. Solve: color by color, vectorized lane =
// constraint (colored_batches.hpp), the same formula for every constraint.
#include "seiche/kernels/distance_constraint.hpp"

#include <algorithm>
#include <cmath>

#include "colored_batches.hpp"
#include "seiche/kernels/graph_coloring.hpp"

namespace seiche::kernels {

std::vector<std::uint32_t> color_distance_constraints(std::span<const std::uint32_t> i,
                                                      std::span<const std::uint32_t> j,
                                                      std::span<const float> rest_length,
                                                      std::span<const float> compliance,
                                                      std::size_t particle_count,
                                                      DistanceConstraints& out) {
  // Greedy coloring of the pairs (graph_coloring.hpp): each constraint takes the lowest color
  // that neither endpoint uses yet; constraints of one color stay in input order.
  const std::size_t m = i.size();
  std::vector<std::uint32_t> pairs(2 * m);
  for (std::size_t c = 0; c < m; ++c) pairs[2 * c] = i[c], pairs[2 * c + 1] = j[c];
  Coloring coloring = color_constraints(pairs, 2, particle_count);
  out.color_start = std::move(coloring.color_start);
  std::vector<std::uint32_t> source = std::move(coloring.order);

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

namespace {

using colored::V3;

/// One XPBD step of distance constraint(s) between p[0] and p[1] (the formula of the header,
/// T = float or Floats): returns dlambda (0 where skipped) and the corrections.
template <class T>
SEICHE_INLINE inline T distance_step(const V3<T> p[2], const T w[2], const T& rest, const T& alpha,
                                     const T& lambda, V3<T> dp[2]) {
  const T zero(0.0f), one(1.0f);
  const T denom = w[0] + w[1] + alpha;
  const V3<T> d = p[0] - p[1];
  const T len = colored::vsqrt(dot(d, d));
  // Skipped: both ends pinned and rigid (nothing can move), or coincident (no direction).
  const colored::MaskOf<T> ok = (denom > zero) & (len > T(1e-9f));
  const T C = len - rest;
  const T dlambda =
      colored::select(ok, (simd::negate(C) - alpha * lambda) / colored::select(ok, denom, one), zero);
  const T s = dlambda / colored::select(ok, len, one);  // dlambda n = s d
  dp[0] = d * (w[0] * s);
  dp[1] = d * simd::negate(w[1] * s);
  return dlambda;
}

}  // namespace

void solve_distance_constraints(const PackedPositions& packed, DistanceConstraints& c, float dt,
                                Multipliers start) {
  const float inv_dt2 = 1.0f / (dt * dt);
  const float* const compliance = c.compliance.data();
  const float* const rest_length = c.rest_length.data();
  float* const lambda = c.lambda.data();
  const bool restart = start == Multipliers::Restart;
  colored::solve_colored<2>(
      packed.by_index(), c.color_start, {c.i.data(), c.j.data()},
      [=](const colored::Batch& batch, const V3<simd::Floats> x[2], const simd::Floats w[2],
          V3<simd::Floats> dp[2]) {
        const simd::Floats alpha = batch.load(compliance) * simd::Floats(inv_dt2);
        const simd::Floats l = restart ? simd::Floats(0.0f) : batch.load(lambda);
        const simd::Floats dlambda = distance_step(x, w, batch.load(rest_length), alpha, l, dp);
        batch.store(lambda, l + dlambda);
      });
}

void solve_distance_constraints(const ParticleView& p, DistanceConstraints& c, float dt) {
  colored::solve_packed(p, {c.i, c.j}, [&](const PackedPositions& packed) {
    solve_distance_constraints(packed, c, dt, Multipliers::Accumulate);
  });
}

DistanceError distance_constraint_error(const ParticleView& p, const DistanceConstraints& c) {
  // Serial: constraint counts of raw constraints are small, and a serial sum is deterministic.
  DistanceError e;
  const std::size_t m = c.size();
  if (m == 0) return e;
  double sum = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    const double rel = edge_strain(p, c.i[k], c.j[k], c.rest_length[k]);
    sum += rel;
    e.max = std::max(e.max, rel);
  }
  e.mean = sum / double(m);
  return e;
}

}  // namespace seiche::kernels
