// The fluid surface level set: see fluid_surface.hpp for the field and why.
//
// Pipeline: bin the particles per voxel leaf (a stable counting sort) -> classify leaves
// (occupied, dense, deep = dense with 26 dense neighbours, band = within a leaf of a particle and
// not deep) -> 1. for every band leaf in parallel, accumulate the kernel sum, the nearest
// distance (and velocity) row by row and turn them into the raw phi -> 2. smooth every leaf with
// its neighbours' halo -> 3. flag the particles left outside, add their beads leaf by leaf ->
// 4. add the band leaves and the deep tiles to the tree in a fixed order and prune.
#include "fluid_surface.hpp"

#include <fmt/format.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/Prune.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

namespace seiche::exporting {
namespace {

using openvdb::Coord;
using FloatLeaf = openvdb::FloatTree::LeafNodeType;
using VectorLeaf = openvdb::Vec3STree::LeafNodeType;

constexpr int kLeafLog2 = 3;
constexpr int kLeafDim = 1 << kLeafLog2;  // 8 voxels
constexpr int kLeafVoxels = kLeafDim * kLeafDim * kLeafDim;
/// A bin is dense when it holds this fraction of the particles a rest lattice puts in a leaf.
constexpr double kDenseFraction = 0.75;
/// phi (voxels) interpolated at a particle is at most minus this: see keep_particles_inside.
constexpr float kInsideMargin = 0.05f;
/// Entries of the table of the inverse half-space profile.
constexpr int kProfileTable = 4096;
/// Index-space coordinates beyond this are refused (int coordinates).
constexpr float kMaxIndex = 1073741824.0f;  // 2^30

/// The kernel sum of the rest lattice (spacing 1, h = kSurfaceKernelRadius) at a point of its
/// unit cell, the smallest one over the cell: c = 1 there, and c >= 1 everywhere inside a rest
/// lattice. (At a lattice site the sum is 5.16; between sites it dips by 2.5 %. Normalising by the
/// site's sum would leave that ripple in the deep interior, where the inverse profile is steep.)
double interior_kernel_sum() {
  const double radius = kSurfaceKernelRadius;
  const int reach = int(std::ceil(radius)) + 1;
  constexpr int kSamples = 8;  // per axis over half the cell; the cell is symmetric
  double smallest = std::numeric_limits<double>::max();
  for (int a = 0; a <= kSamples; ++a)
    for (int b = 0; b <= a; ++b)
      for (int e = 0; e <= b; ++e) {
        const double px = 0.5 * a / kSamples, py = 0.5 * b / kSamples, pz = 0.5 * e / kSamples;
        double sum = 0.0;
        for (int k = -reach; k <= reach; ++k)
          for (int j = -reach; j <= reach; ++j)
            for (int i = -reach; i <= reach; ++i) {
              const double r2 = (i - px) * (i - px) + (j - py) * (j - py) + (k - pz) * (k - pz);
              const double q = 1.0 - r2 / (radius * radius);
              if (q > 0.0) sum += q * q * q;
            }
        smallest = std::min(smallest, sum);
      }
  return smallest;
}

/// G(t) = integral of (1 - t^2)^4: the kernel's mass in a slab, up to constants (a slice of the
/// ball at height t h holds pi h^2 (1 - t^2)^4 / 4 of W).
double slab_mass(double t) {
  const double t2 = t * t;
  return t * (1.0 + t2 * (-4.0 / 3.0 + t2 * (6.0 / 5.0 + t2 * (-4.0 / 7.0 + t2 / 9.0))));
}

/// The half-space profile: the fraction of the kernel's mass inside the fluid for a point at
/// signed distance x h (positive outside) from a flat fluid face, F(x) = (G(1) - G(x)) / 2 G(1);
/// F(-1) = 1, F(0) = 1/2, F(1) = 0.
double half_space_density(double x) {
  x = std::clamp(x, -1.0, 1.0);
  return 0.5 * (1.0 - slab_mass(x) / slab_mass(1.0));
}

/// F^-1 sampled at c = k / kProfileTable (bisection; F is decreasing), for linear interpolation.
const std::vector<float>& inverse_profile_table() {
  static const std::vector<float> table = [] {
    std::vector<float> t(kProfileTable + 1);
    for (int k = 0; k <= kProfileTable; ++k) {
      const double c = double(k) / kProfileTable;
      double lo = -1.0, hi = 1.0;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        (half_space_density(mid) > c ? lo : hi) = mid;
      }
      t[std::size_t(k)] = float(0.5 * (lo + hi));
    }
    return t;
  }();
  return table;
}

/// Signed distance (in kernel radii, positive outside) at which a flat face gives density c.
float distance_from_density(float c, const float* table) {
  const float u = std::clamp(c, 0.0f, 1.0f) * float(kProfileTable);
  const int k = std::min(int(u), kProfileTable - 1);
  const float f = u - float(k);
  return table[k] + f * (table[k + 1] - table[k]);
}

/// Particles grouped per leaf: bin b holds, in input order, the particles whose nearest voxel lies
/// in the leaf at leaf coordinate (origin / 8) `leaf[b]`; their index-space positions (and
/// velocities) are copied in bin order, so that a leaf reads them contiguously.
struct LeafBins {
  std::vector<Coord> leaf;
  std::vector<std::uint32_t> begin;  ///< bin b: [begin[b], begin[b + 1])
  std::vector<float> px, py, pz;     ///< index space (voxel centres at integers)
  std::vector<float> vx, vy, vz;     ///< m/s, when asked
  openvdb::Int32Tree bin_of_leaf{-1};
};

Coord leaf_of(float px, float py, float pz) {
  return Coord(int(std::lround(px)) >> kLeafLog2, int(std::lround(py)) >> kLeafLog2,
               int(std::lround(pz)) >> kLeafLog2);
}

LeafBins bin_particles(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                       std::span<const float> vx, std::span<const float> vy,
                       std::span<const float> vz, float inv_dx) {
  const std::size_t n = x.size();
  // Leaf coordinate of every particle, in parallel; non-finite or absurdly far positions refused.
  std::vector<Coord> leaf(n);
  std::vector<std::uint8_t> bad(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const float p[3] = {x[i] * inv_dx, y[i] * inv_dx, z[i] * inv_dx};
                        bool ok = true;
                        for (const float c : p)
                          ok = ok && std::abs(c) < kMaxIndex;  // false for NaN too
                        bad[i] = !ok;
                        leaf[i] = ok ? leaf_of(p[0], p[1], p[2]) : Coord(0);
                      }
                    });
  for (std::size_t i = 0; i < n; ++i)
    if (bad[i])
      throw std::invalid_argument(
          fmt::format("fluid surface: particle {} at ({}, {}, {}) m is not finite or more than "
                      "2^30 voxels from the origin",
                      i, x[i], y[i], z[i]));

  // Bins in order of first appearance (the store's cell order makes neighbours share a leaf, so
  // the last leaf is checked first), then a stable counting sort of the particles by bin.
  LeafBins bins;
  std::vector<std::uint32_t> bin_of(n);
  std::vector<std::uint32_t> count;
  {
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> bin_of_leaf(bins.bin_of_leaf);
    Coord last = Coord::max();
    int last_bin = -1;
    for (std::size_t i = 0; i < n; ++i) {
      if (leaf[i] != last) {
        if (!bin_of_leaf.probeValue(leaf[i], last_bin)) {
          last_bin = int(bins.leaf.size());
          bin_of_leaf.setValue(leaf[i], last_bin);
          bins.leaf.push_back(leaf[i]);
          count.push_back(0);
        }
        last = leaf[i];
      }
      bin_of[i] = std::uint32_t(last_bin);
      ++count[std::size_t(last_bin)];
    }
  }
  bins.begin.resize(count.size() + 1);
  bins.begin[0] = 0;
  for (std::size_t b = 0; b < count.size(); ++b) bins.begin[b + 1] = bins.begin[b] + count[b];
  const bool with_velocity = !vx.empty();
  bins.px.resize(n), bins.py.resize(n), bins.pz.resize(n);
  if (with_velocity) bins.vx.resize(n), bins.vy.resize(n), bins.vz.resize(n);
  std::vector<std::uint32_t> cursor(bins.begin.begin(), bins.begin.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t k = cursor[bin_of[i]]++;
    bins.px[k] = x[i] * inv_dx, bins.py[k] = y[i] * inv_dx, bins.pz[k] = z[i] * inv_dx;
    if (with_velocity) bins.vx[k] = vx[i], bins.vy[k] = vy[i], bins.vz[k] = vz[i];
  }
  return bins;
}

/// Leaves to compute (band) and leaves known to be inside (deep), as leaf coordinates in tree
/// order.
struct LeafClasses {
  std::vector<Coord> band, deep;
};

LeafClasses classify_leaves(const LeafBins& bins, double dense_count) {
  openvdb::MaskTree reach, deep;
  for (std::size_t b = 0; b < bins.leaf.size(); ++b) {
    reach.setValueOn(bins.leaf[b]);
    if (double(bins.begin[b + 1] - bins.begin[b]) >= dense_count) deep.setValueOn(bins.leaf[b]);
  }
  openvdb::tools::dilateActiveValues(reach, 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::IGNORE_TILES);
  openvdb::tools::erodeActiveValues(deep, 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                    openvdb::tools::IGNORE_TILES);
  reach.topologyDifference(deep);
  reach.voxelizeActiveTiles();
  deep.voxelizeActiveTiles();
  LeafClasses classes;
  for (auto it = reach.cbeginValueOn(); it; ++it) classes.band.push_back(it.getCoord());
  for (auto it = deep.cbeginValueOn(); it; ++it) classes.deep.push_back(it.getCoord());
  return classes;
}

/// Per-voxel sums of one leaf, in the leaf's voxel order (x * 64 + y * 8 + z).
struct LeafSums {
  alignas(64) float c[kLeafVoxels];   ///< sum q^3, q = 1 - r^2 / reach^2
  alignas(64) float d2[kLeafVoxels];  ///< min |x - p|^2 (voxels^2)
  alignas(64) float vx[kLeafVoxels];  ///< sum q^3 v
  alignas(64) float vy[kLeafVoxels];
  alignas(64) float vz[kLeafVoxels];

  void reset() {
    std::fill(std::begin(c), std::end(c), 0.0f);
    std::fill(std::begin(d2), std::end(d2), std::numeric_limits<float>::max());
    std::fill(std::begin(vx), std::end(vx), 0.0f);
    std::fill(std::begin(vy), std::end(vy), 0.0f);
    std::fill(std::begin(vz), std::end(vz), 0.0f);
  }
};

/// First and last voxel index of a leaf row within [lo, hi] (empty when first > last).
inline int first_voxel(float lo) {
  if (!(lo > 0.0f)) return 0;
  const int i = int(lo);  // lo > 0: truncation is floor
  return i + (float(i) < lo);
}
inline int last_voxel(float hi) {
  if (hi >= float(kLeafDim - 1)) return kLeafDim - 1;
  return hi < 0.0f ? -1 : int(hi);
}

/// Distance from t to the leaf's index range [0, 7] along one axis.
inline float outside_leaf(float t) {
  return t < 0.0f ? -t : (t > float(kLeafDim - 1) ? t - float(kLeafDim - 1) : 0.0f);
}

/// Adds one particle at leaf-local index position (px, py, pz) to the voxels within `reach`.
template <bool kVelocity>
void add_particle(LeafSums& s, float px, float py, float pz, float pvx, float pvy, float pvz,
                  float reach, float inv_reach2) {
  const float ox = outside_leaf(px), oy = outside_leaf(py), oz = outside_leaf(pz);
  const float reach2 = reach * reach;
  if (ox * ox + oy * oy + oz * oz >= reach2) return;  // most of the 27 bins' particles
  const float room = reach2 - oz * oz;                // for (x, y) of rows that meet the sphere
  const int x0 = first_voxel(px - reach), x1 = last_voxel(px + reach);
  const int y0 = first_voxel(py - reach), y1 = last_voxel(py + reach);
  for (int ix = x0; ix <= x1; ++ix) {
    const float ddx = float(ix) - px, rx2 = ddx * ddx;
    for (int iy = y0; iy <= y1; ++iy) {
      const float ddy = float(iy) - py, rxy2 = rx2 + ddy * ddy;
      if (rxy2 >= room) continue;
      const int row = (ix << (2 * kLeafLog2)) | (iy << kLeafLog2);
      float* __restrict c = s.c + row;
      float* __restrict d2 = s.d2 + row;
      float* __restrict vx = s.vx + row;
      float* __restrict vy = s.vy + row;
      float* __restrict vz = s.vz + row;
      // Branch-free, so that GCC vectorises the row: max(t, 0) written as (t + |t|) / 2 (exact);
      // not unrolled first, which would leave it to the weaker straight-line vectoriser.
#pragma GCC unroll 1
      for (int iz = 0; iz < kLeafDim; ++iz) {
        const float ddz = float(iz) - pz;
        const float r2 = rxy2 + ddz * ddz;
        const float t = 1.0f - r2 * inv_reach2;
        const float q = (t + std::abs(t)) * 0.5f;
        const float w = q * q * q;
        c[iz] += w;
        d2[iz] = std::min(d2[iz], r2);
        if constexpr (kVelocity) {
          vx[iz] += w * pvx;
          vy[iz] += w * pvy;
          vz[iz] += w * pvz;
        }
      }
    }
  }
}

/// Field constants in voxel units.
struct FieldConstants {
  float reach;          ///< kernel radius h / dx
  float inv_lattice;    ///< 1 / (smallest kernel sum inside a rest lattice)
  float sphere_radius;  ///< r / dx
  float erosion;        ///< e / dx
  float half_width;     ///< w
  float voxel_size;     ///< dx (m)
};

using LeafValues = std::array<float, kLeafVoxels>;

/// Raw phi (voxels, clamped to +-w) of every voxel of a leaf from its sums.
void raw_phi(const LeafSums& s, const FieldConstants& k, const float* profile, LeafValues& phi) {
  const float reach2 = k.reach * k.reach;
  for (int v = 0; v < kLeafVoxels; ++v)
    phi[v] = k.reach * distance_from_density(s.c[v] * k.inv_lattice, profile);
  for (int v = 0; v < kLeafVoxels; ++v) {
    const float sphere = s.d2[v] < reach2 ? std::sqrt(s.d2[v]) - k.sphere_radius : k.half_width;
    phi[v] = std::clamp(std::min(phi[v], sphere) + k.erosion, -k.half_width, k.half_width);
  }
}

/// v = sum q^3 v_p / sum q^3 wherever the kernel reaches, marked active there (the final mask is
/// this and the surface's band).
void velocity_values(const LeafSums& s, VectorLeaf& leaf) {
  for (int v = 0; v < kLeafVoxels; ++v) {
    if (!(s.c[v] > 0.0f)) continue;
    const float inv = 1.0f / s.c[v];
    leaf.setValueOn(openvdb::Index(v), openvdb::Vec3s(s.vx[v] * inv, s.vy[v] * inv, s.vz[v] * inv));
  }
}

/// The computed leaves' values by leaf coordinate: index into `values` (>= 0), kDeepLeaf (inside,
/// -w) or the background (outside, +w).
constexpr int kDeepLeaf = -2;
struct LeafLookup {
  const openvdb::Int32Tree& index;
  const std::vector<LeafValues>& values;
  float half_width;
};

/// Copies the (8 + 2 kHalo)^3 block around the leaf at `leaf_coord` (the leaf and a halo of
/// kHalo voxels from its 26 neighbours) out of `lookup`.
template <int kHalo>
void gather_block(const LeafLookup& lookup,
                  openvdb::tree::ValueAccessor<const openvdb::Int32Tree>& index,
                  const Coord& leaf_coord, float* block) {
  constexpr int kBlock = kLeafDim + 2 * kHalo;
  for (int di = -1; di <= 1; ++di)
    for (int dj = -1; dj <= 1; ++dj)
      for (int dk = -1; dk <= 1; ++dk) {
        // The part of neighbour (di, dj, dk) inside the block, in the neighbour's local
        // coordinates.
        const auto range = [](int d, int& lo, int& hi) {
          lo = d < 0 ? kLeafDim - kHalo : 0;
          hi = d > 0 ? kHalo - 1 : kLeafDim - 1;
        };
        int i0, i1, j0, j1, k0, k1;
        range(di, i0, i1), range(dj, j0, j1), range(dk, k0, k1);
        const int l = index.getValue(leaf_coord.offsetBy(di, dj, dk));
        const float* src = l >= 0 ? lookup.values[std::size_t(l)].data() : nullptr;
        const float fill = l == kDeepLeaf ? -lookup.half_width : lookup.half_width;
        for (int i = i0; i <= i1; ++i)
          for (int j = j0; j <= j1; ++j) {
            const int bi = i + kHalo + di * kLeafDim, bj = j + kHalo + dj * kLeafDim;
            float* dst = block + (bi * kBlock + bj) * kBlock + kHalo + dk * kLeafDim;
            for (int m = k0; m <= k1; ++m)
              dst[m] = src ? src[(i << (2 * kLeafLog2)) | (j << kLeafLog2) | m] : fill;
          }
      }
}

/// kPasses passes of the separable 3-voxel box filter (the mean filter of LevelSetFilter, without
/// its renormalisation: it moves flat faces not at all and rounds bumps of a voxel or two) of
/// the block around one leaf; the leaf's smoothed values go to `out`.
template <int kPasses>
void smooth_leaf(const float* block_in, LeafValues& out) {
  constexpr int kBlock = kLeafDim + 2 * kPasses;
  constexpr int kCount = kBlock * kBlock * kBlock;
  std::array<float, kCount> a, b;
  std::copy(block_in, block_in + kCount, a.begin());
  const auto at = [](int i, int j, int m) { return (i * kBlock + j) * kBlock + m; };
  constexpr float kThird = 1.0f / 3.0f;
  for (int pass = 0; pass < kPasses; ++pass) {
    // Each pass leaves one more layer of the block's border stale; kPasses layers are the halo.
    b = a;
    for (int i = 0; i < kBlock; ++i)
      for (int j = 0; j < kBlock; ++j)
        for (int m = 1; m + 1 < kBlock; ++m)
          b[at(i, j, m)] = (a[at(i, j, m - 1)] + a[at(i, j, m)] + a[at(i, j, m + 1)]) * kThird;
    a = b;
    for (int i = 0; i < kBlock; ++i)
      for (int j = 1; j + 1 < kBlock; ++j)
        for (int m = 0; m < kBlock; ++m)
          a[at(i, j, m)] = (b[at(i, j - 1, m)] + b[at(i, j, m)] + b[at(i, j + 1, m)]) * kThird;
    b = a;
    for (int i = 1; i + 1 < kBlock; ++i)
      for (int j = 0; j < kBlock; ++j)
        for (int m = 0; m < kBlock; ++m)
          a[at(i, j, m)] = (b[at(i - 1, j, m)] + b[at(i, j, m)] + b[at(i + 1, j, m)]) * kThird;
  }
  for (int i = 0; i < kLeafDim; ++i)
    for (int j = 0; j < kLeafDim; ++j)
      for (int m = 0; m < kLeafDim; ++m)
        out[std::size_t((i << (2 * kLeafLog2)) | (j << kLeafLog2) | m)] =
            a[at(i + kPasses, j + kPasses, m + kPasses)];
}

/// phi (voxels) of `lookup` at index-space point p, trilinearly interpolated.
float sample(const LeafLookup& lookup,
             openvdb::tree::ValueAccessor<const openvdb::Int32Tree>& index, float px, float py,
             float pz) {
  const int x0 = int(std::floor(px)), y0 = int(std::floor(py)), z0 = int(std::floor(pz));
  const float fx = px - float(x0), fy = py - float(y0), fz = pz - float(z0);
  float value = 0.0f;
  for (int corner = 0; corner < 8; ++corner) {
    const Coord c(x0 + (corner & 1), y0 + ((corner >> 1) & 1), z0 + (corner >> 2));
    const int l = index.getValue(c >> kLeafLog2);
    const float v = l >= 0 ? lookup.values[std::size_t(l)][std::size_t(FloatLeaf::coordToOffset(c))]
                           : (l == kDeepLeaf ? -lookup.half_width : lookup.half_width);
    value += ((corner & 1) ? fx : 1 - fx) * (((corner >> 1) & 1) ? fy : 1 - fy) *
             ((corner >> 2) ? fz : 1 - fz) * v;
  }
  return value;
}

/// Lowers the 8 voxels around p (the corners of its cell) by `deficit` below their smoothed
/// value, so that phi interpolated at p drops by that much (the weights sum to 1).
void lift_cell(LeafValues& phi, const LeafValues& smoothed, float px, float py, float pz,
               float deficit) {
  const int cx = int(std::floor(px)), cy = int(std::floor(py)), cz = int(std::floor(pz));
  for (int ix = std::max(cx, 0); ix <= std::min(cx + 1, kLeafDim - 1); ++ix)
    for (int iy = std::max(cy, 0); iy <= std::min(cy + 1, kLeafDim - 1); ++iy)
      for (int iz = std::max(cz, 0); iz <= std::min(cz + 1, kLeafDim - 1); ++iz) {
        const std::size_t v = std::size_t((ix << (2 * kLeafLog2)) | (iy << kLeafLog2) | iz);
        phi[v] = std::min(phi[v], smoothed[v] - deficit);
      }
}

/// phi = min(phi, |x - p| - radius) around the particle at leaf-local index position p, within
/// the band.
void add_bead(LeafValues& phi, float px, float py, float pz, float radius, float half_width) {
  const float reach = radius + half_width, reach2 = reach * reach;
  const int x0 = first_voxel(px - reach), x1 = last_voxel(px + reach);
  const int y0 = first_voxel(py - reach), y1 = last_voxel(py + reach);
  const int z0 = first_voxel(pz - reach), z1 = last_voxel(pz + reach);
  for (int ix = x0; ix <= x1; ++ix)
    for (int iy = y0; iy <= y1; ++iy)
      for (int iz = z0; iz <= z1; ++iz) {
        const float dx = float(ix) - px, dy = float(iy) - py, dz = float(iz) - pz;
        const float r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= reach2) continue;
        float& v = phi[std::size_t((ix << (2 * kLeafLog2)) | (iy << kLeafLog2) | iz)];
        v = std::min(v, std::sqrt(r2) - radius);
      }
}

/// Every particle inside after trilinear interpolation. With beads of radius rho > sqrt(3)/2
/// voxel (the default voxel size) this holds already: phi at the 8 corners of the cell holding p
/// is at most |corner - p| - rho, and the trilinear weights average |corner - p| to at most
/// sqrt(3)/2. For coarser voxels, the particles whose interpolated phi is above -kInsideMargin
/// get their nearest voxel (the largest weight) lowered until it is -kInsideMargin, in particle
/// order (lowering a voxel only helps the others).
void keep_particles_inside(openvdb::FloatGrid& grid, std::span<const float> x,
                           std::span<const float> y, std::span<const float> z, float half_width) {
  const double dx = grid.voxelSize()[0];
  const float margin = float(kInsideMargin * dx), floor = -half_width * float(dx);
  std::vector<std::uint8_t> outside(x.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      const openvdb::FloatGrid::ConstAccessor acc = grid.getConstAccessor();
                      const openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor,
                                                        openvdb::tools::BoxSampler>
                          phi(acc, grid.transform());
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        outside[i] = phi.wsSample(openvdb::Vec3d(x[i], y[i], z[i])) > -margin;
                    });
  openvdb::FloatGrid::Accessor acc = grid.getAccessor();
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!outside[i]) continue;
    const openvdb::Vec3d p = grid.worldToIndex(openvdb::Vec3d(x[i], y[i], z[i]));
    const Coord base = Coord::floor(p);
    const openvdb::Vec3d f = p - base.asVec3d();
    double value = 0.0, nearest_weight = 0.0, nearest_value = 0.0;
    Coord nearest = base;
    for (int corner = 0; corner < 8; ++corner) {
      const Coord c = base.offsetBy(corner & 1, (corner >> 1) & 1, corner >> 2);
      const double w = ((corner & 1) ? f[0] : 1 - f[0]) * (((corner >> 1) & 1) ? f[1] : 1 - f[1]) *
                       ((corner >> 2) ? f[2] : 1 - f[2]);
      const double v = acc.getValue(c);
      value += w * v;
      if (w > nearest_weight) nearest_weight = w, nearest_value = v, nearest = c;
    }
    if (value <= -margin || nearest_weight <= 0.0) continue;
    const double lowered = nearest_value - (value + margin) / nearest_weight;
    acc.setValueOn(nearest, std::max(floor, float(lowered)));
  }
}

void check_shape(const SurfaceShape& shape) {
  const float s = shape.spacing, dx = shape.voxel_size;
  if (!(std::isfinite(s) && s > 0.0f))
    throw std::invalid_argument(fmt::format("fluid surface: spacing must be > 0 m, got {}", s));
  if (!(std::isfinite(dx) && dx >= 0.25f * s && dx <= s))
    throw std::invalid_argument(
        fmt::format("fluid surface: voxel size {} m is out of range [{}, {}] m (a quarter of the "
                    "spacing {} m to the spacing)",
                    dx, 0.25f * s, s, s));
  if (shape.smoothing_passes < 0 || shape.smoothing_passes > 2)
    throw std::invalid_argument(
        fmt::format("fluid surface: {} smoothing passes (0, 1 or 2)", shape.smoothing_passes));
  if (!(shape.half_width >= 1.0f && shape.half_width <= 16.0f))
    throw std::invalid_argument(fmt::format(
        "fluid surface: half width {} voxels is out of range [1, 16]", shape.half_width));
}

}  // namespace

openvdb::math::Transform::Ptr voxel_transform(float voxel_size) {
  return openvdb::math::Transform::createLinearTransform(double(voxel_size));
}

FluidSurfaceGrids fluid_surface(std::span<const float> x, std::span<const float> y,
                                std::span<const float> z, std::span<const float> vx,
                                std::span<const float> vy, std::span<const float> vz,
                                const SurfaceShape& shape, bool with_velocity) {
  check_shape(shape);
  const std::size_t n = x.size();
  if (y.size() != n || z.size() != n ||
      (with_velocity && (vx.size() != n || vy.size() != n || vz.size() != n)))
    throw std::invalid_argument("fluid surface: position and velocity arrays differ in length");
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("fluid surface: more than 2^32 - 1 particles");

  const float dx = shape.voxel_size;
  const float background = shape.half_width * dx;
  FluidSurfaceGrids out;
  out.surface = openvdb::FloatGrid::create(background);
  out.surface->setTransform(voxel_transform(dx));
  out.surface->setGridClass(openvdb::GRID_LEVEL_SET);
  if (with_velocity) {
    out.velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    out.velocity->setTransform(voxel_transform(dx));
    out.velocity->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
  }
  if (n == 0) return out;

  const std::span<const float> none;
  const LeafBins bins = with_velocity ? bin_particles(x, y, z, vx, vy, vz, 1.0f / dx)
                                      : bin_particles(x, y, z, none, none, none, 1.0f / dx);
  const double rest_per_leaf = std::pow(double(kLeafDim) * dx / shape.spacing, 3.0);
  const LeafClasses classes = classify_leaves(bins, kDenseFraction * rest_per_leaf);

  static const double lattice_sum = interior_kernel_sum();
  FieldConstants k;
  k.reach = kSurfaceKernelRadius * shape.spacing / dx;
  k.inv_lattice = float(1.0 / lattice_sum);
  const float* profile = inverse_profile_table().data();
  const float inv_reach2 = 1.0f / (k.reach * k.reach);
  k.sphere_radius = kParticleSphereRadius * shape.spacing / dx;
  k.erosion = shape.smoothing_passes > 0 ? kErosion * shape.spacing / dx : 0.0f;
  k.half_width = shape.half_width;
  k.voxel_size = dx;

  // 1. The raw field of every band leaf, in parallel (and the velocities, where the kernel
  // reaches).
  const std::size_t leaf_count = classes.band.size();
  std::vector<LeafValues> raw(leaf_count);
  std::vector<std::unique_ptr<VectorLeaf>> velocity_leaves(with_velocity ? leaf_count : 0);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, leaf_count, 2),
      [&](const tbb::blocked_range<std::size_t>& r) {
        auto sums = std::make_unique<LeafSums>();
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> bin_of_leaf(bins.bin_of_leaf);
        for (std::size_t l = r.begin(); l != r.end(); ++l) {
          const Coord leaf_coord = classes.band[l];
          const Coord origin = leaf_coord << kLeafLog2;
          sums->reset();
          for (int i = -1; i <= 1; ++i)
            for (int j = -1; j <= 1; ++j)
              for (int m = -1; m <= 1; ++m) {
                const int b = bin_of_leaf.getValue(leaf_coord.offsetBy(i, j, m));
                if (b < 0) continue;
                for (std::uint32_t p = bins.begin[std::size_t(b)];
                     p < bins.begin[std::size_t(b) + 1]; ++p) {
                  const float px = bins.px[p] - float(origin.x()),
                              py = bins.py[p] - float(origin.y()),
                              pz = bins.pz[p] - float(origin.z());
                  if (with_velocity)
                    add_particle<true>(*sums, px, py, pz, bins.vx[p], bins.vy[p], bins.vz[p],
                                       k.reach, inv_reach2);
                  else
                    add_particle<false>(*sums, px, py, pz, 0.0f, 0.0f, 0.0f, k.reach, inv_reach2);
                }
              }
          raw_phi(*sums, k, profile, raw[l]);
          if (with_velocity) {
            velocity_leaves[l] = std::make_unique<VectorLeaf>(origin, openvdb::Vec3s(0.0f));
            velocity_values(*sums, *velocity_leaves[l]);
          }
        }
      });

  // Which computed leaf holds a leaf coordinate (for the smoothing's halos and the sampling).
  openvdb::Int32Tree leaf_index(-1);
  {
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> index(leaf_index);
    for (const Coord& c : classes.deep) index.setValue(c, kDeepLeaf);
    for (std::size_t l = 0; l < leaf_count; ++l) index.setValue(classes.band[l], int(l));
  }

  // 2. Smoothing: every leaf reads the raw field of its neighbours and writes its own.
  std::vector<LeafValues> phi;
  if (shape.smoothing_passes == 0) {
    phi = std::move(raw);
  } else {
    phi.resize(leaf_count);
    const LeafLookup lookup{leaf_index, raw, k.half_width};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaf_count, 4),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(leaf_index);
                        std::vector<float> block(std::size_t(std::pow(kLeafDim + 2 * 2, 3)));
                        for (std::size_t l = r.begin(); l != r.end(); ++l) {
                          if (shape.smoothing_passes == 1) {
                            gather_block<1>(lookup, index, classes.band[l], block.data());
                            smooth_leaf<1>(block.data(), phi[l]);
                          } else {
                            gather_block<2>(lookup, index, classes.band[l], block.data());
                            smooth_leaf<2>(block.data(), phi[l]);
                          }
                        }
                      });
    raw = {};
  }

  // 3. Every particle inside: the smoothing leaves out the high points of a rough surface layer
  //    (their deficit phi(p) + margin is positive) and lone spray. The first get the least lift
  //    that takes them in (their cell's 8 voxels lowered by the deficit), spray further out than
  //    a bead's radius gets a bead. Deficits first, from the smoothed field (read only), then
  //    every leaf applies those of its neighbourhood to its own voxels.
  std::vector<float> outside(n, 0.0f);  // phi at the particle + margin when that is > 0, else 0
  const std::uint32_t outside_count = [&] {
    const LeafLookup lookup{leaf_index, phi, k.half_width};
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, 4096), std::uint32_t(0),
        [&](const tbb::blocked_range<std::size_t>& r, std::uint32_t count) {
          openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(leaf_index);
          for (std::size_t p = r.begin(); p != r.end(); ++p) {
            const float deficit =
                sample(lookup, index, bins.px[p], bins.py[p], bins.pz[p]) + kInsideMargin;
            outside[p] = deficit > 0.0f ? deficit : 0.0f;
            count += deficit > 0.0f;
          }
          return count;
        },
        std::plus<>());
  }();
  if (outside_count > 0) {
    const float bead_radius = kBeadRadius * shape.spacing / dx;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, leaf_count, 4),
        [&](const tbb::blocked_range<std::size_t>& r) {
          openvdb::tree::ValueAccessor<const openvdb::Int32Tree> bin_of_leaf(bins.bin_of_leaf);
          for (std::size_t l = r.begin(); l != r.end(); ++l) {
            const Coord origin = classes.band[l] << kLeafLog2;
            const LeafValues smoothed = phi[l];
            for (int i = -1; i <= 1; ++i)
              for (int j = -1; j <= 1; ++j)
                for (int m = -1; m <= 1; ++m) {
                  const int b = bin_of_leaf.getValue(classes.band[l].offsetBy(i, j, m));
                  if (b < 0) continue;
                  for (std::uint32_t p = bins.begin[std::size_t(b)];
                       p < bins.begin[std::size_t(b) + 1]; ++p) {
                    if (!(outside[p] > 0.0f)) continue;
                    const float px = bins.px[p] - float(origin.x()),
                                py = bins.py[p] - float(origin.y()),
                                pz = bins.pz[p] - float(origin.z());
                    if (outside[p] > bead_radius)  // spray: a droplet of its own
                      add_bead(phi[l], px, py, pz, bead_radius, k.half_width);
                    else
                      lift_cell(phi[l], smoothed, px, py, pz, outside[p]);
                  }
                }
          }
        });
  }

  // 4. The trees, in a fixed order: deep tiles, then every band leaf as a leaf (some active
  //    voxel, or both signs), an inside tile (all -w) or nothing (all +w).
  openvdb::FloatTree& tree = out.surface->tree();
  for (const Coord& leaf_coord : classes.deep)
    tree.addTile(1, leaf_coord << kLeafLog2, -background, false);
  for (std::size_t l = 0; l < leaf_count; ++l) {
    const Coord origin = classes.band[l] << kLeafLog2;
    auto leaf = std::make_unique<FloatLeaf>(origin, background);
    float* values = leaf->buffer().data();
    FloatLeaf::NodeMaskType on;
    int negative = 0;
    for (int v = 0; v < kLeafVoxels; ++v) {
      const float value = std::clamp(phi[l][std::size_t(v)], -k.half_width, k.half_width);
      values[v] = value * dx;
      if (std::abs(value) < k.half_width) on.setOn(openvdb::Index(v));
      negative += value < 0.0f;
    }
    if (on.isOff() && negative == kLeafVoxels) tree.addTile(1, origin, -background, false);
    if (on.isOff() && (negative == 0 || negative == kLeafVoxels)) continue;
    leaf->setValueMask(on);
    tree.addLeaf(leaf.release());
    if (with_velocity) {
      velocity_leaves[l]->setValueMask(velocity_leaves[l]->getValueMask() & on);
      out.velocity->tree().addLeaf(velocity_leaves[l].release());
    }
  }
  if (0.5f * std::sqrt(3.0f) - kBeadRadius * shape.spacing / dx > -kInsideMargin)
    keep_particles_inside(*out.surface, x, y, z, shape.half_width);
  openvdb::tools::pruneLevelSet(tree);
  if (with_velocity) openvdb::tools::pruneInactive(out.velocity->tree());
  return out;
}

}  // namespace seiche::exporting
