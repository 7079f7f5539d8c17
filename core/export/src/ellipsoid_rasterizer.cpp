// Narrow-band level set of a union of ellipsoids, in three passes.
//
// 1. Rasterize near the surface. For an ellipsoid with centre c, G = sum_k u_k u_k^T / a_k and a
//    point x, let d = x - c, q = G d, g = G q. The implicit function f = |q| - 1 is zero on the
//    surface with gradient g / |q|, so its first-order distance is f / |grad f| = f |q| / |g|.
//    Two bounds hold everywhere: |G v| <= |v| / a_min puts the nearest surface point at least
//    a_min |f| away, and the surface point c + d / |q| on the ray is (|d| / |q|) |f| away; no
//    point is deeper than a_min. Hence
//        phi = max(f * clamp(|q| / |g|, a_min, |d| / |q|), -a_min),
//    exact along every axis (the three lengths all equal a_k there) and at the zero crossing.
//    Each ellipsoid writes min(old, phi) over its bounding box grown by 1.5 voxels, enough for
//    every voxel next to the zero crossing to get its value; deeper voxels only need the sign.
// 2. Redistance. A min of ellipsoid distances is the distance to the union outside, but inside it
//    is the depth in the deepest single ellipsoid: between the centres of a block of spheres of
//    radius 2 voxels it reads -0.3 voxel, far from the -3 voxels of a true distance (and the
//    first-order estimate above can read deeper than the truth inside a flat ellipsoid). So the
//    band is rebuilt from the shells, the voxels with a 6-neighbour of the other sign, whose
//    pass-1 values are within a voxel of the crossing and hence accurate. For a voxel x and a
//    shell voxel y on the other side, the segment x-y crosses the surface, so
//        |x - y| >= D(x) + |phi(y)|,   i.e.   D(x) <= |x - y| - |phi(y)|,
//    with equality when y lies on x's normal (the error is that of the best y's offset from the
//    normal: e^2 / 2|x - y|, a few hundredths of a voxel to 0.3). Every shell voxel
//    scatters |x - y| - |phi(y)| to the voxels of the other sign within half_width + 1 voxels,
//    and each voxel keeps the smallest. Shell voxels keep their pass-1 values, so the zero
//    crossing does not move; every other voxel takes its sign from pass 1 and its distance from
//    here, except that outside, where pass 1 within its band is already the distance to the
//    union, the smaller of the two is kept (on a sphere: 0.01-0.03 voxel of mean error, 0.3 at
//    most, instead of 0.04-0.08).
// 3. Clamp to [-background, background], activate |phi| < background, signedFloodFill, prune.
//
// Per-voxel work in pass 1 runs over the eight contiguous floats of a leaf's z-row and avoids
// libm (inverse_sqrt below), so it vectorises. Parallelism: TBB workers write into their own
// trees, merged by an elementwise min. min is exact and order-independent once -0 is folded into
// +0 (+ 0.0f), and every value is computed from absolute voxel coordinates, so the grid is the
// same bit for bit whichever thread did what.
#include "ellipsoid_rasterizer.hpp"

#include <openvdb/tools/Prune.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

namespace seiche::exporting {
namespace {

using openvdb::Coord;
using openvdb::FloatTree;
using openvdb::Vec3d;
using openvdb::Vec3f;
using LeafT = FloatTree::LeafNodeType;
using Accessor = openvdb::tree::ValueAccessor<FloatTree>;
constexpr int kLeafDim = int(LeafT::DIM);  // 8
constexpr float kRasterBandVoxels = 1.5f;  // pass 1 band: covers every voxel next to a crossing
constexpr float kFar = std::numeric_limits<float>::max();

// 1 / sqrt(x) for x > 0, without libm: std::sqrt may set errno, which keeps GCC from vectorising
// a loop that calls it. The bit-level estimate (relative error < 0.2 %) after two Newton steps
// is within 5e-6 (relative): 1e-5 voxel on a distance of two voxels.
inline float inverse_sqrt(float x) {
  float y = std::bit_cast<float>(0x5f375a86u - (std::bit_cast<std::uint32_t>(x) >> 1));
  y = y * (1.5f - 0.5f * x * y * y);
  return y * (1.5f - 0.5f * x * y * y);
}

// Row-major 3x3 in float: m[r][c].
struct Mat3f {
  float m[3][3];
  Vec3f col(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
};

Mat3f multiply(const Mat3f& a, const Mat3f& b) {
  Mat3f r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += double(a.m[i][k]) * double(b.m[k][j]);
      r.m[i][j] = float(s);
    }
  return r;
}

// The linear part M of index -> world (x_world = M ijk + offset).
Mat3f index_to_world_linear(const openvdb::math::Transform& transform) {
  if (!transform.isLinear())
    throw std::invalid_argument(
        "rasterize_ellipsoids: the transform must be linear (affine), got " + transform.mapType());
  Mat3f m{};
  const Vec3d offset = transform.indexToWorld(Vec3d(0.0));
  for (int c = 0; c < 3; ++c) {
    Vec3d unit(0.0);
    unit[c] = 1.0;
    const Vec3d column = transform.indexToWorld(unit) - offset;
    for (int row = 0; row < 3; ++row) m.m[row][c] = float(column[row]);
  }
  return m;
}

// One ellipsoid ready for pass 1: its index-space centre and the matrices that map an
// index-space offset e = ijk - centre to d = M e, q = G M e and g = G G M e (world units).
struct PreparedEllipsoid {
  Vec3d center_index;
  Mat3f to_d, to_q, to_g;
  float a_min;
  Coord lo, hi;  // index bounding box grown by the raster band (inclusive)
};

PreparedEllipsoid prepare(const Ellipsoid& e, const Mat3f& index_to_world,
                          const openvdb::math::Transform& transform, float band) {
  PreparedEllipsoid p{};
  Mat3f g{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k)
        s += double(e.axes[k][i]) * double(e.axes[k][j]) / double(e.semi_axes[k]);
      g.m[i][j] = float(s);
    }
  p.to_d = index_to_world;
  p.to_q = multiply(g, index_to_world);
  p.to_g = multiply(g, p.to_q);
  p.a_min = std::min({e.semi_axes[0], e.semi_axes[1], e.semi_axes[2]});
  p.center_index = transform.worldToIndex(Vec3d(e.center));

  // World half-extent along axis w: sqrt(sum_k (a_k u_k[w])^2), plus the band; then the index
  // box of the eight corners.
  Vec3d half;
  for (int w = 0; w < 3; ++w) {
    double s = 0;
    for (int k = 0; k < 3; ++k) s += std::pow(double(e.semi_axes[k]) * double(e.axes[k][w]), 2);
    half[w] = std::sqrt(s) + double(band);
  }
  Vec3d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3d world(e.center[0] + ((corner & 1) ? half[0] : -half[0]),
                      e.center[1] + ((corner & 2) ? half[1] : -half[1]),
                      e.center[2] + ((corner & 4) ? half[2] : -half[2]));
    const Vec3d index = transform.worldToIndex(world);
    lo = openvdb::math::minComponent(lo, index);
    hi = openvdb::math::maxComponent(hi, index);
  }
  // Index coordinates are 32-bit: an ellipsoid beyond 2^30 voxels from the origin is dropped.
  constexpr double kMaxIndex = double(1 << 30);
  for (int k = 0; k < 3; ++k)
    if (!(std::abs(lo[k]) < kMaxIndex && std::abs(hi[k]) < kMaxIndex)) {
      p.lo = Coord(1);
      p.hi = Coord(0);  // empty box
      return p;
    }
  p.lo = Coord(int(std::ceil(lo[0])), int(std::ceil(lo[1])), int(std::ceil(lo[2])));
  p.hi = Coord(int(std::floor(hi[0])), int(std::floor(hi[1])), int(std::floor(hi[2])));
  return p;
}

inline Vec3f times(const Mat3f& m, float x, float y) {
  return {m.m[0][0] * x + m.m[0][1] * y, m.m[1][0] * x + m.m[1][1] * y,
          m.m[2][0] * x + m.m[2][1] * y};
}

// row[k] = min(row[k], phi_k) for a z-row, phi from the three lengths of the comment on top.
// (Not inlined: inlined, GCC 12 loses the __restrict and leaves this loop scalar.)
[[gnu::noinline]] void min_into_row(float* __restrict row, const float* __restrict q_len,
                                    const float* __restrict gradient_length,
                                    const float* __restrict ray_length,
                                    const float* __restrict box_mask, float a_min) {
  for (int k = 0; k < kLeafDim; ++k) {
    const float length =
        std::min(std::max(gradient_length[k], a_min), std::max(ray_length[k], a_min));
    const float phi = std::max((q_len[k] - 1.0f) * length, -a_min) + 0.0f;  // + 0.0f: -0 -> +0
    row[k] = std::min(row[k], std::max(phi, box_mask[k]));
  }
}

// Pass 1 for one ellipsoid and one leaf: min(old, phi) on the voxels of its box.
void rasterize_into_leaf(const PreparedEllipsoid& p, LeafT& leaf) {
  const Coord o = leaf.origin();
  const int x0 = std::max(p.lo.x(), o.x()), x1 = std::min(p.hi.x(), o.x() + kLeafDim - 1);
  const int y0 = std::max(p.lo.y(), o.y()), y1 = std::min(p.hi.y(), o.y() + kLeafDim - 1);
  const int z0 = p.lo.z() - o.z(), z1 = p.hi.z() - o.z();  // leaf-local, may exceed 0..7
  const Vec3f dz = p.to_d.col(2), qz = p.to_q.col(2), gz = p.to_g.col(2);
  constexpr float kTiny = 1e-30f;
  // Leaf-local z outside [z0, z1] (the box) gets +kFar, inside -kFar: phi = max(phi, this).
  float ez[kLeafDim], box_mask[kLeafDim];
  for (int k = 0; k < kLeafDim; ++k) {
    ez[k] = float(double(o.z() + k) - p.center_index[2]);
    box_mask[k] = (k >= z0 && k <= z1) ? -kFar : kFar;
  }
  const float a_min = p.a_min;
  float* values = leaf.buffer().data();

  // Two loops over the eight contiguous voxels of a z-row, each simple enough to vectorise.
  float q_len[kLeafDim], gradient_length[kLeafDim], ray_length[kLeafDim];
  for (int x = x0; x <= x1; ++x) {
    const float ex = float(double(x) - p.center_index[0]);
    for (int y = y0; y <= y1; ++y) {
      const float ey = float(double(y) - p.center_index[1]);
      const Vec3f d_row = times(p.to_d, ex, ey), q_row = times(p.to_q, ex, ey),
                  g_row = times(p.to_g, ex, ey);
      for (int k = 0; k < kLeafDim; ++k) {
        const float d0 = d_row[0] + dz[0] * ez[k], d1 = d_row[1] + dz[1] * ez[k],
                    d2 = d_row[2] + dz[2] * ez[k];
        const float q0 = q_row[0] + qz[0] * ez[k], q1 = q_row[1] + qz[1] * ez[k],
                    q2 = q_row[2] + qz[2] * ez[k];
        const float g0 = g_row[0] + gz[0] * ez[k], g1 = g_row[1] + gz[1] * ez[k],
                    g2 = g_row[2] + gz[2] * ez[k];
        const float dd = d0 * d0 + d1 * d1 + d2 * d2 + kTiny;  // + kTiny: no 0 in inverse_sqrt
        const float qq = q0 * q0 + q1 * q1 + q2 * q2 + kTiny;
        const float gg = g0 * g0 + g1 * g1 + g2 * g2 + kTiny;
        const float inv_q = inverse_sqrt(qq);
        q_len[k] = qq * inv_q;                             // at d = 0 all three lengths are ~0
        gradient_length[k] = q_len[k] * inverse_sqrt(gg);  // f / |grad f| = f * this
        ray_length[k] = dd * inverse_sqrt(dd) * inv_q;
      }
      min_into_row(values + LeafT::coordToOffset(Coord(x, y, o.z())), q_len, gradient_length,
                   ray_length, box_mask, a_min);
    }
  }
}

// Calls leaf_op(leaf) for every leaf of [lo, hi], creating it (full of the background) if absent.
template <typename LeafOp>
void for_each_leaf_in(const Coord& lo, const Coord& hi, Accessor& acc, LeafOp leaf_op) {
  const int mask = ~(kLeafDim - 1);
  for (int lx = lo.x() & mask; lx <= hi.x(); lx += kLeafDim)
    for (int ly = lo.y() & mask; ly <= hi.y(); ly += kLeafDim)
      for (int lz = lo.z() & mask; lz <= hi.z(); lz += kLeafDim)
        leaf_op(*acc.touchLeaf(Coord(lx, ly, lz)));
}

// target = min(target, source) voxel by voxel; leaves only in source are copied.
void merge_min(FloatTree& target, const FloatTree& source) {
  for (auto it = source.cbeginLeaf(); it; ++it) {
    LeafT* leaf = target.probeLeaf(it->origin());
    if (!leaf) {
      target.addLeaf(new LeafT(*it));
      continue;
    }
    float* dst = leaf->buffer().data();
    const float* src = it->buffer().data();
    for (openvdb::Index n = 0; n < LeafT::SIZE; ++n) dst[n] = std::min(dst[n], src[n]);
  }
}

// Runs write(i, accessor) for i in [0, count) on TBB workers, each into its own tree (background
// `background`), and returns their elementwise min.
template <typename Write>
std::shared_ptr<FloatTree> parallel_min_tree(std::size_t count, std::size_t grain, float background,
                                             Write write) {
  tbb::enumerable_thread_specific<std::shared_ptr<FloatTree>> per_thread;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      auto& tree = per_thread.local();
                      if (!tree) tree = std::make_shared<FloatTree>(background);
                      Accessor acc(*tree);
                      for (std::size_t i = r.begin(); i != r.end(); ++i) write(i, acc);
                    });
  std::shared_ptr<FloatTree> result;
  for (auto& tree : per_thread) {
    if (!tree) continue;
    if (!result)
      result = tree;
    else
      merge_min(*result, *tree);
  }
  return result ? result : std::make_shared<FloatTree>(background);
}

// ---- Pass 2: redistance from the shells ----------------------------------------------------

struct ShellVoxel {
  Coord ijk;
  float value;  // pass-1 value, |value| <= about a voxel
};

struct Shells {
  std::vector<LeafT*> leaves;                   // pass-1 leaves, in LeafManager order
  std::vector<std::vector<ShellVoxel>> voxels;  // per leaf
  std::vector<LeafT::NodeMaskType> masks;       // per leaf: which voxels are shell voxels
};

// Also marks active the inside voxels off the shell, so that pass 2 can skip the leaves with none
// when scattering from outside shell voxels.
Shells find_shells(FloatTree& tree) {
  openvdb::tree::LeafManager<FloatTree> manager(tree);
  Shells shells;
  shells.leaves.resize(manager.leafCount());
  shells.voxels.resize(manager.leafCount());
  shells.masks.resize(manager.leafCount());
  const FloatTree& read = tree;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, manager.leafCount(), 16),
      [&](const tbb::blocked_range<std::size_t>& r) {
        openvdb::tree::ValueAccessor<const FloatTree> acc(read);
        for (std::size_t l = r.begin(); l != r.end(); ++l) {
          LeafT& leaf = manager.leaf(l);
          shells.leaves[l] = &leaf;
          const float* values = leaf.buffer().data();
          // The six face-neighbour leaves (null: untouched, outside), as -x, +x, -y, +y, -z, +z.
          const float* next[6];
          for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
              Coord o = leaf.origin();
              o[axis] += side ? kLeafDim : -kLeafDim;
              const LeafT* neighbour = acc.probeConstLeaf(o);
              next[2 * axis + side] = neighbour ? neighbour->buffer().data() : nullptr;
            }
          // Value at leaf-local (x, y, z), each coordinate in -1..8.
          auto value_at = [&](int x, int y, int z) -> float {
            int axis = -1, side = 0;
            if (x < 0 || x >= kLeafDim)
              axis = 0, side = x >= kLeafDim;
            else if (y < 0 || y >= kLeafDim)
              axis = 1, side = y >= kLeafDim;
            else if (z < 0 || z >= kLeafDim)
              axis = 2, side = z >= kLeafDim;
            if (axis < 0) return values[LeafT::coordToOffset(Coord(x, y, z))];
            const float* other = next[2 * axis + side];
            if (!other) return 1.0f;  // outside
            return other[LeafT::coordToOffset(
                Coord(x & (kLeafDim - 1), y & (kLeafDim - 1), z & (kLeafDim - 1)))];
          };
          for (int x = 0; x < kLeafDim; ++x)
            for (int y = 0; y < kLeafDim; ++y)
              for (int z = 0; z < kLeafDim; ++z) {
                const openvdb::Index n = LeafT::coordToOffset(Coord(x, y, z));
                const bool inside = values[n] < 0.0f;
                const bool shell = (value_at(x - 1, y, z) < 0.0f) != inside ||
                                   (value_at(x + 1, y, z) < 0.0f) != inside ||
                                   (value_at(x, y - 1, z) < 0.0f) != inside ||
                                   (value_at(x, y + 1, z) < 0.0f) != inside ||
                                   (value_at(x, y, z - 1) < 0.0f) != inside ||
                                   (value_at(x, y, z + 1) < 0.0f) != inside;
                if (shell) {
                  shells.voxels[l].push_back({leaf.origin() + Coord(x, y, z), values[n]});
                  shells.masks[l].setOn(n);
                }
                leaf.setActiveState(n, inside && !shell);
              }
        }
      });
  return shells;
}

// |x - y| (world units) for the offsets x - y = (dx, dy, dz) that can matter: |x - y| <= (half
// width + 1) voxels, the rest +kFar. Laid out as one z-row per (dx, dy), padded by a leaf on both
// sides, so a leaf's z-row of eight voxels reads eight consecutive entries.
struct OffsetDistances {
  int reach;       // voxels
  int row_length;  // 2 * (reach + kLeafDim) - 1
  // Entry of (dx, dy, dz): [(dx + reach) * side + (dy + reach)] * row_length + dz + reach + 7.
  std::vector<float> table;
  std::vector<int> row_reach;  // per (dx, dy): the largest |dz| with a finite entry, -1 if none

  int reach_of_row(int dx, int dy) const {
    return row_reach[std::size_t((dx + reach) * (2 * reach + 1) + (dy + reach))];
  }

  std::size_t index(int dx, int dy, int dz) const {
    const int side = 2 * reach + 1;
    return std::size_t((dx + reach) * side + (dy + reach)) * std::size_t(row_length) +
           std::size_t(dz + reach + kLeafDim - 1);
  }
  /// The eight distances of offsets (dx, dy, dz_first .. dz_first + 7).
  const float* row(int dx, int dy, int dz_first) const {
    return table.data() + index(dx, dy, dz_first);
  }
};

OffsetDistances offset_distances(float half_width, float voxel) {
  OffsetDistances o;
  o.reach = int(std::ceil(half_width)) + 1;
  o.row_length = 2 * (o.reach + kLeafDim) - 1;
  const int side = 2 * o.reach + 1;
  const double max_distance = double(half_width) + 1.0;
  o.table.assign(std::size_t(side) * side * std::size_t(o.row_length), kFar);
  o.row_reach.assign(std::size_t(side) * side, -1);
  for (int dx = -o.reach; dx <= o.reach; ++dx)
    for (int dy = -o.reach; dy <= o.reach; ++dy)
      for (int dz = -o.reach; dz <= o.reach; ++dz) {
        const double distance = std::sqrt(double(dx * dx + dy * dy + dz * dz));
        if (distance > max_distance) continue;
        o.table[o.index(dx, dy, dz)] = float(distance) * voxel;
        int& row_reach = o.row_reach[std::size_t((dx + o.reach) * side + (dy + o.reach))];
        row_reach = std::max(row_reach, std::abs(dz));
      }
  return o;
}

// depth[k] = min(depth[k], max(distance[k] - y_distance, 0)) on the voxels of the other sign than
// the shell voxel y (inside: value < 0). Not inlined, as min_into_row.
template <bool kShellInside>
[[gnu::noinline]] void min_into_other_side(float* __restrict depth, const float* __restrict sign,
                                           const float* __restrict distance, float y_distance) {
  for (int k = 0; k < kLeafDim; ++k) {
    const bool other_side = kShellInside ? !(sign[k] < 0.0f) : sign[k] < 0.0f;
    // + 0.0f (-0 -> +0) before the max: after it, GCC 12 no longer vectorises the loop.
    const float bound = std::max(distance[k] - y_distance + 0.0f, 0.0f);
    depth[k] = std::min(depth[k], other_side ? bound : kFar);
  }
}

// Scatters |x - y| - |phi(y)| from the shell voxels y of one leaf to the voxels x of the other
// sign around them, leaf by leaf of the target region.
void scatter_shell_voxels(std::span<const ShellVoxel> shell, const OffsetDistances& offsets,
                          openvdb::tree::ValueAccessor<const FloatTree>& pass1, Accessor& depth,
                          float background) {
  if (shell.empty()) return;
  Coord lo = shell[0].ijk, hi = shell[0].ijk;
  for (const ShellVoxel& y : shell) {
    lo.minComponent(y.ijk);
    hi.maxComponent(y.ijk);
  }
  lo = lo.offsetBy(-offsets.reach);
  hi = hi.offsetBy(offsets.reach);
  float outside_row[kLeafDim];
  std::fill(outside_row, outside_row + kLeafDim, background);
  const int mask = ~(kLeafDim - 1);
  for (int lx = lo.x() & mask; lx <= hi.x(); lx += kLeafDim)
    for (int ly = lo.y() & mask; ly <= hi.y(); ly += kLeafDim)
      for (int lz = lo.z() & mask; lz <= hi.z(); lz += kLeafDim) {
        const Coord o(lx, ly, lz);
        const LeafT* pass1_leaf = pass1.probeConstLeaf(o);  // absent: untouched by pass 1, outside
        const bool has_inside_targets = pass1_leaf && !pass1_leaf->isEmpty();  // see find_shells
        LeafT* target = nullptr;
        for (const ShellVoxel& y : shell) {
          if (y.value >= 0.0f && !has_inside_targets) continue;  // outside y only serves inside x
          const Coord a = Coord::maxComponent(y.ijk.offsetBy(-offsets.reach), o);
          const Coord b =
              Coord::minComponent(y.ijk.offsetBy(offsets.reach), o.offsetBy(kLeafDim - 1));
          if (a.x() > b.x() || a.y() > b.y() || a.z() > b.z()) continue;
          if (!target) target = depth.touchLeaf(o);
          float* values = target->buffer().data();
          const float y_distance = std::abs(y.value);
          for (int x = a.x(); x <= b.x(); ++x)
            for (int yy = a.y(); yy <= b.y(); ++yy) {
              const int dz_reach = offsets.reach_of_row(x - y.ijk.x(), yy - y.ijk.y());
              if (lz > y.ijk.z() + dz_reach || lz + kLeafDim - 1 < y.ijk.z() - dz_reach) continue;
              const openvdb::Index n = LeafT::coordToOffset(Coord(x, yy, lz));
              const float* sign = pass1_leaf ? pass1_leaf->buffer().data() + n : outside_row;
              const float* distance = offsets.row(x - y.ijk.x(), yy - y.ijk.y(), lz - y.ijk.z());
              if (y.value < 0.0f)
                min_into_other_side<true>(values + n, sign, distance, y_distance);
              else
                min_into_other_side<false>(values + n, sign, distance, y_distance);
            }
        }
      }
}

// Final value of one voxel: a shell voxel keeps its pass-1 value, any other takes the sign of its
// pass-1 value and the scattered distance (outside: or its pass-1 value if smaller).
inline float redistanced(float raster, float scattered, bool shell, float background) {
  const float phi = shell ? raster : raster < 0.0f ? -scattered : std::min(raster, scattered);
  return std::clamp(phi, -background, background) + 0.0f;
}

}  // namespace

openvdb::FloatGrid::Ptr rasterize_ellipsoids(std::span<const Ellipsoid> ellipsoids,
                                             const openvdb::math::Transform::Ptr& transform,
                                             float half_width) {
  if (!transform) throw std::invalid_argument("rasterize_ellipsoids: null transform");
  const float voxel = float(transform->voxelSize()[0]);
  const float background = half_width * voxel;
  if (!(half_width >= 1.0f) || !std::isfinite(background) || !(voxel > 0.0f))
    throw std::invalid_argument(
        "rasterize_ellipsoids: half_width must be >= 1 and the voxel size positive");
  const Mat3f index_to_world = index_to_world_linear(*transform);

  // Pass 1. Leaves are created full of +background: untouched voxels read as outside.
  const float raster_band = std::min(kRasterBandVoxels * voxel, background);
  auto tree =
      parallel_min_tree(ellipsoids.size(), 64, background, [&](std::size_t i, Accessor& acc) {
        const PreparedEllipsoid p = prepare(ellipsoids[i], index_to_world, *transform, raster_band);
        for_each_leaf_in(p.lo, p.hi, acc, [&](LeafT& leaf) { rasterize_into_leaf(p, leaf); });
      });

  // Pass 2.
  Shells shells = find_shells(*tree);
  const OffsetDistances offsets = offset_distances(half_width, voxel);
  const FloatTree& signs = *tree;
  auto scattered =
      parallel_min_tree(shells.leaves.size(), 4, background, [&](std::size_t l, Accessor& acc) {
        openvdb::tree::ValueAccessor<const FloatTree> pass1(signs);
        scatter_shell_voxels(shells.voxels[l], offsets, pass1, acc, background);
      });
  for (auto it = scattered->cbeginLeaf(); it; ++it)  // voxels only pass 2 reached: outside
    if (!tree->probeLeaf(it->origin())) {
      shells.leaves.push_back(tree->touchLeaf(it->origin()));
      shells.masks.emplace_back();
    }

  // Pass 3.
  const FloatTree& scattered_read = *scattered;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, shells.leaves.size(), 16),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t l = r.begin(); l != r.end(); ++l) {
          LeafT& leaf = *shells.leaves[l];
          const LeafT* scattered_leaf = scattered_read.probeConstLeaf(leaf.origin());
          float* values = leaf.buffer().data();
          for (openvdb::Index n = 0; n < LeafT::SIZE; ++n) {
            const float bound = scattered_leaf ? scattered_leaf->getValue(n) : background;
            values[n] = redistanced(values[n], bound, shells.masks[l].isOn(n), background);
            leaf.setActiveState(n, std::abs(values[n]) < background);
          }
        }
      });
  openvdb::tools::signedFloodFill(*tree);
  openvdb::tools::pruneLevelSet(*tree);

  auto grid = openvdb::FloatGrid::create(tree);
  grid->setTransform(transform);
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  return grid;
}

}  // namespace seiche::exporting
