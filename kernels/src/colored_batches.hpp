// Colored constraint solves vectorized lane = constraint (internal to kernels/): the distance
// constraints and both bending models.
//
// Colors run one after another; inside a color, kLanes consecutive constraints form a batch, the
// batches run in parallel. A batch gathers its constraints' particles (predicted positions and
// inverse masses), the family's step computes every lane's correction, and the new positions
// are scattered back. No two constraints of a color share a particle, so the lanes of a batch
// and the batches of a color never touch the same particle. The last batch of a color is
// padded by repeating its last constraint; padding lanes compute like the others and are not
// stored. Every constraint thus goes through the same lane arithmetic (no scalar tail, no
// horizontal operation), and the result is bit-identical with any thread count.
//
// The solves work on the particles packed as (px, py, pz, w) records (PackedPositions,
// packed_positions.hpp): a lane's particle is one 16-byte load and one 16-byte store. The
// ParticleView entry points pack and unpack around one family (solve_packed below); the
// simulation packs once for all the families it solves in a row (its iteration record).
//
// The families' steps are templates on the number type T (float or Floats), with the small
// vector type and overloads below, so that they read as the scalar formulas they are; the
// solves instantiate them with Floats. sqrt, division and the basic operations are correctly
// rounded in both, and simd::atan2 runs the same operations for both, so T = float is meant to
// give the same bits lane for lane (tested bit for bit for atan2 only, tests/simd_tests.cpp).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <type_traits>
#include <utility>

#include "seiche/kernels/packed_positions.hpp"
#include "seiche/kernels/particle_view.hpp"
#include "simd.hpp"

namespace seiche::kernels::colored {

using simd::Floats;
using simd::kLanes;

template <class T>
struct V3 {
  T x, y, z;
};
template <class T>
inline V3<T> operator+(const V3<T>& u, const V3<T>& v) {
  return {u.x + v.x, u.y + v.y, u.z + v.z};
}
template <class T>
inline V3<T> operator-(const V3<T>& u, const V3<T>& v) {
  return {u.x - v.x, u.y - v.y, u.z - v.z};
}
template <class T>
inline V3<T> operator*(const V3<T>& u, const T& s) {
  return {u.x * s, u.y * s, u.z * s};
}
template <class T>
inline T dot(const V3<T>& u, const V3<T>& v) {
  return u.x * v.x + u.y * v.y + u.z * v.z;
}
template <class T>
inline V3<T> cross(const V3<T>& u, const V3<T>& v) {
  return {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
}

/// The comparison result of T: bool for float, a lane mask for Floats.
template <class T>
using MaskOf = std::conditional_t<std::is_same_v<T, float>, bool, simd::Mask>;
inline float select(bool m, float a, float b) { return m ? a : b; }
inline Floats select(const simd::Mask& m, const Floats& a, const Floats& b) {
  return xsimd::select(m, a, b);
}
inline float vsqrt(float x) { return std::sqrt(x); }  // both correctly rounded: same bits
inline Floats vsqrt(const Floats& x) { return xsimd::sqrt(x); }

/// kLanes consecutive constraints [i, i + active) of one color: simd::Lanes over the
/// constraints' columns (load and store of a partial batch included).
struct Batch : simd::Lanes {
  /// Constraint of lane l: padding lanes repeat the last active constraint.
  std::size_t at(std::size_t l) const { return i + std::min(l, active - 1); }
};

/// body(std::integral_constant<std::size_t, s>) for s = 0 .. N - 1.
template <std::size_t N, class Body>
SEICHE_INLINE inline void for_each_slot(Body&& body) {
  [&]<std::size_t... S>(std::index_sequence<S...>) {
    (body(std::integral_constant<std::size_t, S>{}), ...);
  }
  (std::make_index_sequence<N>{});
}

/// One batch: gather, step, scatter. Full is known at compile time, so a full batch (all but at
/// most one per color) runs without lane checks; a partial one runs the same lane arithmetic.
/// Everything arrives by value: the 16-byte stores may alias anything, and values in registers
/// need no reload after them.
template <bool Full, std::size_t N, class Step>
SEICHE_INLINE inline void solve_batch(Float4* records, std::array<const std::uint32_t*, N> vertex,
                                      Batch batch, Step step) {
  V3<Floats> x[N], dp[N];
  Floats w[N];
  // Slot by slot, unrolled at compile time (constant indices keep x, w, dp in registers).
  for_each_slot<N>([&](auto s) {
    const std::uint32_t* column = vertex[s];
    const simd::Gathered4 g =
        Full ? simd::gather4(records, [&](std::size_t l) { return column[batch.i + l]; })
             : simd::gather4(records, [&](std::size_t l) { return column[batch.at(l)]; });
    x[s] = {g.x, g.y, g.z};
    w[s] = g.w;
  });
  step(batch, x, w, dp);
  for_each_slot<N>([&](auto s) {
    // The slot's indices from this batch on, through simd::opaque: else g++ reuses the 8 N index
    // addresses of the gather, keeps them across the step and spills them (12 % of the step's
    // instructions, measured at 100 x 100); this way each is one load at an offset.
    const std::uint32_t* column = vertex[s] + batch.i;
    simd::opaque(column);
    simd::scatter4(
        records, [&](std::size_t l) { return column[l]; }, x[s].x + dp[s].x, x[s].y + dp[s].y,
        x[s].z + dp[s].z, w[s], Full ? kLanes : batch.active);
  });
}

/// Solves every color of a colored family of N-particle constraints on the packed records
/// (PackedPositions::by_index(), which must cover every index of the columns): vertex[s] is the
/// column of the constraints' s-th particle index. step(batch, positions x[N], inverse masses
/// w[N], corrections dp[N]) computes the lanes' corrections (and updates the family's own
/// columns, such as lambda, through batch.load and batch.store); x + dp is then scattered back.
/// step is copied by value into every task: give it the raw pointers it needs, captured by value.
template <std::size_t N, class Step>
void solve_colored(Float4* records, std::span<const std::uint32_t> color_start,
                   const std::array<const std::uint32_t*, N>& vertex, const Step& step) {
  for (std::size_t color = 0; color + 1 < color_start.size(); ++color) {
    const std::size_t begin = color_start[color], end = color_start[color + 1];
    const std::size_t full_batches = (end - begin) / kLanes;
    // A static partition: every color is split alike, so each thread keeps working on the same
    // part of the mesh (constraints are stored in mesh order inside a color) and its particles
    // stay in its core's cache from one color to the next.
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, full_batches, 16),
        [=](const auto& r) {
          for (std::size_t bi = r.begin(); bi != r.end(); ++bi)
            solve_batch<true>(records, vertex, Batch{{begin + bi * kLanes, kLanes}}, step);
        },
        tbb::static_partitioner());
    const std::size_t tail = begin + full_batches * kLanes;
    if (tail < end) solve_batch<false>(records, vertex, Batch{{tail, end - tail}}, step);
  }
}

/// One family solved on its own: packs the range its index columns use, runs
/// solve(PackedPositions&), unpacks. The entry points that take a ParticleView use it (a family
/// solved once, or a test); the simulation keeps one PackedPositions across families instead.
template <class Solve>
void solve_packed(const ParticleView& p,
                  std::initializer_list<std::span<const std::uint32_t>> columns, Solve&& solve) {
  PackedPositions packed;
  packed.reset(index_range(columns));
  if (packed.range().empty()) return;
  packed.pack(p);
  solve(packed);
  packed.unpack(p);
}

}  // namespace seiche::kernels::colored
