// Neighbor lists (CSR) from a sorted CellGrid.
//
// Candidates. For the 9 (dz, dy) rows around a particle's cell, the cells cx-1..cx+1 of a row are
// ONE contiguous range of sorted indices (keys are x-fastest), and rows taken in increasing
// (dz, dy) have increasing indices: scanning them in that order yields each list already sorted.
// Distance tests run W particles at a time (xsimd batch) over those ranges with unaligned loads
// of the SoA positions; each lane's result becomes one bit, lanes past the range are masked off.
//
// Culling. The 27 cells hold about 8x the true neighbors. When the grid has no more cells than
// particles, each cell gets the bounding box of its particles, and per query one W-wide test
// "squared gap to the box < r^2" keeps only the cells that can hold a neighbor; each row is then
// scanned from its first to its last kept cell. The gap is computed with the same float
// operations as the distance (differences, squares, left-to-right sum) and rounding is monotonic,
// so a culled cell provably holds no particle that passes |d|^2 < r^2: culling changes the time,
// never the result.
//
// Output. Particles are processed in waves of fixed blocks; each block writes its lists to its own
// scratch buffer, then the wave's offsets are summed in order and the buffers copied into place.
// One distance pass instead of count-then-fill, a fixed split (deterministic), and scratch memory
// bounded by one wave whatever the particle count.
//
// Particles with a non-finite coordinate have no neighbors and are no one's neighbor (their
// distance is inf or NaN, which fails the test); boxes leave them out.
#include "seiche/neighbor/neighbor_list.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <xsimd/xsimd.hpp>

namespace seiche::neighbor {
namespace {

using Batch = xsimd::batch<float>;
constexpr std::size_t W = Batch::size;
constexpr std::size_t kGrain = 2048;              // particles per block
constexpr std::size_t kWave = 16 * kGrain;        // particles per wave (scratch ~ 4 MB)
constexpr float kInf = std::numeric_limits<float>::infinity();

// ---- SIMD glue xsimd 8.1 lacks (batch_bool::mask() and compress arrived in later versions) ----

inline std::uint32_t lane_bits(const xsimd::batch_bool<float>& b) {
#if XSIMD_WITH_AVX512F
  return std::uint32_t(__mmask16(b));  // already a k-mask
#elif XSIMD_WITH_AVX
  return std::uint32_t(_mm256_movemask_ps(b));
#elif XSIMD_WITH_SSE2
  return std::uint32_t(_mm_movemask_ps(b));
#else
  bool lanes[W];
  b.store_unaligned(lanes);
  std::uint32_t bits = 0;
  for (std::size_t l = 0; l < W; ++l) bits |= std::uint32_t(lanes[l]) << l;
  return bits;
#endif
}

// Writes first + (each set lane of bits), in increasing order, to out[0..popcount). The AVX2
// version stores W slots at once (junk past popcount), out must have room for W: one store and
// no branch per neighbor instead of a mispredicted branch per neighbor.
#if XSIMD_WITH_AVX2 && !XSIMD_WITH_AVX512F
constexpr std::array<std::uint64_t, 256> kPackLanes = [] {  // set lanes of bits, one byte each
  std::array<std::uint64_t, 256> t{};
  for (unsigned bits = 0; bits < 256; ++bits)
    for (unsigned l = 0, k = 0; l < 8; ++l)
      if (bits >> l & 1) t[bits] |= std::uint64_t(l) << (8 * k++);
  return t;
}();
inline void pack_indices(std::uint32_t first, std::uint32_t bits, std::uint32_t* out) {
  const __m256i lanes = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(std::int64_t(kPackLanes[bits])));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out),
                      _mm256_add_epi32(lanes, _mm256_set1_epi32(std::int32_t(first))));
}
#else
inline void pack_indices(std::uint32_t first, std::uint32_t bits, std::uint32_t* out) {
  for (; bits != 0; bits &= bits - 1) *out++ = first + std::uint32_t(std::countr_zero(bits));
}
#endif

// ---- Per-cell bounding boxes (SoA, slot = key + 1: one empty slot before, two after) -----------

struct Boxes {
  std::vector<float> lo[3], hi[3];
};

void compute_boxes(const CellGrid& g, const float* const p[3], Boxes& boxes) {
  const std::size_t cells = g.spec().cell_count();
  for (int a = 0; a < 3; ++a) {
    boxes.lo[a].assign(cells + 3, kInf);
    boxes.hi[a].assign(cells + 3, -kInf);
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells, 4096), [&](const auto& r) {
    for (std::size_t c = r.begin(); c < r.end(); ++c)
      for (std::uint32_t j = g.cell_begin(std::uint32_t(c)); j < g.cell_end(std::uint32_t(c)); ++j) {
        const float q[3] = {p[0][j], p[1][j], p[2][j]};
        if (!(std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]))) continue;
        for (int a = 0; a < 3; ++a) {
          boxes.lo[a][c + 1] = std::min(boxes.lo[a][c + 1], q[a]);
          boxes.hi[a][c + 1] = std::max(boxes.hi[a][c + 1], q[a]);
        }
      }
  });
}

// ---- Per-cell stencil and per-particle query ----------------------------------------------------

// What every particle of one cell needs: the row ranges around the cell and, when culling, the
// boxes of its 27 cells.
struct Stencil {
  std::uint32_t begin = 0, end = 0;  // sorted range of the centre cell (empty: none yet)
  std::int32_t side = 3;             // 2 * reach + 1 cells per row
  std::vector<std::uint32_t> off;    // per row: side + 1 cell boundaries in sorted order
  std::uint32_t candidates = 0;      // particles in all rows: a bound on any list
  bool culled = false;
  alignas(64) float lo[3][32], hi[3][32];  // culled: boxes of the 27 cells, row-major

  void gather(const CellGrid& g, const std::int32_t c[3], std::int32_t reach, const Boxes* boxes) {
    const std::int32_t* d = g.spec().dims;
    side = 2 * reach + 1;
    culled = boxes != nullptr;
    const std::size_t rows = std::size_t(side) * side;
    off.assign(rows * (side + 1), 0);
    candidates = 0;
    for (std::int32_t dz = 0; dz < side; ++dz)
      for (std::int32_t dy = 0; dy < side; ++dy) {
        const std::size_t row = std::size_t(dz) * side + dy;
        const std::int32_t zz = c[2] - reach + dz, yy = c[1] - reach + dy;
        const bool valid = zz >= 0 && zz < d[2] && yy >= 0 && yy < d[1];
        if (valid) {
          // Boundary t is the start of cell cx - reach + t clamped to the row; the start of
          // "cell nx" is the end of the row's last cell.
          std::uint32_t* o = &off[row * (side + 1)];
          const std::uint32_t row_key = g.cell_index(0, yy, zz);
          for (std::int32_t t = 0; t <= side; ++t)
            o[t] = g.cell_begin(row_key + std::uint32_t(std::clamp(c[0] - reach + t, 0, d[0])));
          candidates += o[side] - o[0];
        }
        if (!culled) continue;
        // Boxes of cells cx-1..cx+1 (4 floats copied, the 4th is overwritten by the next row).
        // At the x borders the box belongs to a neighbouring row's cell, harmless: that cell's
        // sorted range here is empty.
        const std::size_t slot = valid ? std::size_t(g.cell_index(c[0], yy, zz)) : 0;
        for (int a = 0; a < 3; ++a) {
          if (valid) {
            std::memcpy(&lo[a][3 * row], &boxes->lo[a][slot], 4 * sizeof(float));
            std::memcpy(&hi[a][3 * row], &boxes->hi[a][slot], 4 * sizeof(float));
          } else {
            std::fill_n(&lo[a][3 * row], 3, kInf);
            std::fill_n(&hi[a][3 * row], 3, -kInf);
          }
        }
      }
    if (culled)
      for (int a = 0; a < 3; ++a) std::fill_n(&lo[a][27], 5, kInf), std::fill_n(&hi[a][27], 5, -kInf);
  }

  // One query: the particle's position broadcast, the squared radius, its list so far.
  struct Query {
    const float* const* p;
    std::size_t n;
    std::uint32_t i;
    Batch qx, qy, qz, rr;
    std::uint32_t* out;
    std::uint32_t count = 0;

    // Lanes of candidates k..k+W-1 within the radius.
    template <bool kSafe>
    std::uint32_t test(std::uint32_t k) const {
      Batch cx, cy, cz;
      if (kSafe) {
        cx = Batch::load_unaligned(p[0] + k);
        cy = Batch::load_unaligned(p[1] + k);
        cz = Batch::load_unaligned(p[2] + k);
      } else {  // the last particles of the arrays: never read past n
        alignas(64) float t[3][W] = {};
        for (std::size_t l = 0; k + l < n && l < W; ++l)
          t[0][l] = p[0][k + l], t[1][l] = p[1][k + l], t[2][l] = p[2][k + l];
        cx = Batch::load_aligned(t[0]), cy = Batch::load_aligned(t[1]), cz = Batch::load_aligned(t[2]);
      }
      const Batch dx = qx - cx, dy = qy - cy, dz = qz - cz;
      return lane_bits(dx * dx + dy * dy + dz * dz < rr);
    }

    template <bool kSafe, bool kSelf>
    void emit(std::uint32_t k, std::uint32_t bits) {
      if (kSelf && i - k < W) bits &= ~(1u << (i - k));  // unsigned: only when k <= i < k + W
      pack_indices(k, bits, out + count);
      count += std::uint32_t(std::popcount(bits));
    }

    // Candidates [b, e): full batches, then one masked batch for the rest.
    template <bool kSafe, bool kSelf>
    void scan(std::uint32_t b, std::uint32_t e) {
      std::uint32_t k = b;
      for (; k + W <= e; k += W) emit<kSafe, kSelf>(k, test<kSafe>(k));
      if (k < e) emit<kSafe, kSelf>(k, test<kSafe>(k) & ((1u << (e - k)) - 1));
    }
    void scan(std::uint32_t b, std::uint32_t e, bool self) {
      if (e + W - 1 <= n)  // the last batch reads up to e + W - 2
        self ? scan<true, true>(b, e) : scan<true, false>(b, e);
      else
        self ? scan<false, true>(b, e) : scan<false, false>(b, e);
    }
  };

  // Writes the neighbors of sorted particle i to out (room for candidates + W) and returns
  // their count.
  std::uint32_t query(const float* const p[3], std::size_t n, std::uint32_t i, float r2,
                      std::uint32_t* out) const {
    if (!(std::isfinite(p[0][i]) && std::isfinite(p[1][i]) && std::isfinite(p[2][i]))) return 0;
    Query q{p, n, i, Batch(p[0][i]), Batch(p[1][i]), Batch(p[2][i]), Batch(r2), out};

    if (!culled) {
      const std::size_t rows = std::size_t(side) * side, centre = rows / 2;
      for (std::size_t r = 0; r < rows; ++r) q.scan(off[r * (side + 1)], off[r * (side + 1) + side], r == centre);
      return q.count;
    }
    std::uint32_t live = 0;  // bit per cell of the 27
    const Batch zero(0.0f);
    for (std::size_t c = 0; c < 32; c += W) {
      const Batch gx = xsimd::max(xsimd::max(Batch::load_aligned(&lo[0][c]) - q.qx, q.qx - Batch::load_aligned(&hi[0][c])), zero);
      const Batch gy = xsimd::max(xsimd::max(Batch::load_aligned(&lo[1][c]) - q.qy, q.qy - Batch::load_aligned(&hi[1][c])), zero);
      const Batch gz = xsimd::max(xsimd::max(Batch::load_aligned(&lo[2][c]) - q.qz, q.qz - Batch::load_aligned(&hi[2][c])), zero);
      live |= lane_bits(gx * gx + gy * gy + gz * gz < q.rr) << c;
    }
    // Visit rows with a kept cell, in row order: bit 3r of `rows` stands for row r.
    for (std::uint32_t rows = (live | live >> 1 | live >> 2) & 01111111111u; rows != 0; rows &= rows - 1) {
      const auto first = unsigned(std::countr_zero(rows)), r = first / 3;
      const std::uint32_t row_live = live >> first & 7u;
      const std::uint32_t* o = &off[r * 4];
      q.scan(o[std::countr_zero(row_live)], o[std::bit_width(row_live)], r == 4);
    }
    return q.count;
  }
};

// Lets `v` hold `needed` entries, growing to `estimate` at once (not doubling) to keep memory
// close to the final size.
void make_room(std::vector<std::uint32_t>& v, std::size_t needed, std::size_t estimate) {
  if (needed > v.capacity()) v.reserve(std::max(needed, estimate));
}

}  // namespace

std::size_t NeighborList::bytes() const {
  return (offsets.capacity() + indices.capacity()) * sizeof(std::uint32_t);
}

void build_neighbor_list(const CellGrid& grid, const float* x, const float* y, const float* z,
                         std::size_t n, float radius, NeighborList& out) {
  if (n != grid.order().size())
    throw std::invalid_argument("seiche::neighbor::build_neighbor_list: n differs from the grid's particle count");
  const std::size_t m = grid.num_in_grid();  // sorted [0, m) are in cells; the rest have no list
  out.offsets.assign(n + 1, 0);
  out.indices.clear();  // keeps its storage for reuse
  if (!(radius > 0) || m == 0) return;
  const float* const p[3] = {x, y, z};
  const float r2 = radius * radius;

  // How many cells away a neighbor can be: 1 when radius <= cell_size, the usual case.
  const std::int32_t* d = grid.spec().dims;
  const double cells_away = std::ceil(double(radius) / double(grid.spec().cell_size));
  const auto reach = std::int32_t(std::clamp(std::isnan(cells_away) ? 1.0 : cells_away, 1.0,
                                             double(std::max({d[0], d[1], d[2]}))));
  // Boxes cost 24 bytes a cell: only when cells are no more numerous than particles.
  Boxes boxes;
  const bool cull = reach == 1 && grid.spec().cell_count() <= n;
  if (cull) compute_boxes(grid, p, boxes);

  struct Block {
    Stencil stencil;
    std::vector<std::uint32_t> lists;
    std::size_t used = 0;
  };
  std::vector<Block> blocks(kWave / kGrain);
  std::uint32_t* const counts = out.offsets.data() + 1;  // count of i at counts[i], summed below

  for (std::size_t w0 = 0; w0 < m; w0 += kWave) {
    const std::size_t w1 = std::min(m, w0 + kWave);
    const std::size_t nblocks = (w1 - w0 + kGrain - 1) / kGrain;
    tbb::parallel_for(std::size_t(0), nblocks, [&](std::size_t b) {
      Block& blk = blocks[b];
      Stencil& s = blk.stencil;
      blk.used = 0;
      for (std::size_t i = w0 + b * kGrain, e = std::min(w1, i + kGrain); i < e; ++i) {
        if (i < s.begin || i >= s.end) {
          std::int32_t c[3];
          grid.cell_of(x[i], y[i], z[i], c);
          const std::uint32_t cell = grid.cell_index(c[0], c[1], c[2]);
          s.gather(grid, c, reach, cull ? &boxes : nullptr);
          s.begin = grid.cell_begin(cell), s.end = grid.cell_end(cell);
        }
        if (blk.lists.size() < blk.used + s.candidates + W)
          blk.lists.resize(2 * (blk.used + s.candidates + W));
        const std::uint32_t c = s.query(p, n, std::uint32_t(i), r2, blk.lists.data() + blk.used);
        blk.used += c;
        counts[i] = c;
      }
    });
    // Offsets of the wave, in order, then the blocks' lists copied into place.
    std::uint64_t sum = out.offsets[w0];
    for (std::size_t i = w0; i < w1; ++i) out.offsets[i + 1] = std::uint32_t(sum += counts[i]);
    if (sum > std::numeric_limits<std::uint32_t>::max())
      throw std::length_error("seiche::neighbor::build_neighbor_list: more than 2^32-1 neighbor entries");
    make_room(out.indices, sum, std::size_t(double(sum) / double(w1) * double(m) * 1.0625));
    out.indices.resize(sum);
    tbb::parallel_for(std::size_t(0), nblocks, [&](std::size_t b) {
      std::copy_n(blocks[b].lists.data(), blocks[b].used,
                  out.indices.data() + out.offsets[w0 + b * kGrain]);
    });
  }
  std::fill(out.offsets.begin() + std::ptrdiff_t(m) + 1, out.offsets.end(), out.offsets[m]);
  if (out.indices.capacity() - out.indices.size() > out.indices.size() / 8) out.indices.shrink_to_fit();
}

}  // namespace seiche::neighbor
