// Neighbor lists (CSR) from a sorted CellGrid.
//
// Work is done per group: the particles of one cell that fall in one work block (usually the
// whole cell). Everything a particle's query needs is shared by its group and computed once:
//
// 1. Rows. For the (2R+1)^2 (dz, dy) rows around the cell (R = 1 when radius <= cell size), the
//    cells cx-R..cx+R of a row are ONE contiguous range of sorted indices (keys are x-fastest),
//    and rows taken in increasing (dz, dy) have increasing indices.
// 2. Culling against the group's box. The group's finite particles have a bounding box; each
//    candidate of the rows is kept when its squared gap to that box is < r^2 (W candidates at a
//    time, xsimd batches), and the kept ones are compacted, in row order (so in increasing j),
//    into a small SoA buffer (x, y, z, j) padded to a multiple of W with +inf positions. The gap
//    is computed with the same float operations as the distance (differences, squares,
//    left-to-right sum) and rounding is monotonic, so a culled candidate provably fails
//    |x_i - x_j|^2 < r^2 for every particle of the group: culling changes the time, never the
//    result. On a lattice with cells of 2 spacings this keeps ~85 of the ~216 row candidates.
// 3. Each particle of the group then tests the compacted candidates: a fixed trip count, no
//    per-particle setup, no tail masks (the padding fails the test), its own index masked out
//    by comparing j, the passing j left-packed (simd::left_pack: a permute or a compress) and
//    stored, one store per W candidates.
//
// Output. Particles are processed in waves of fixed blocks; each block writes its lists to its own
// scratch buffer, then the wave's offsets are summed in order and the buffers copied into place.
// The result depends on nothing but the input: not on the thread count, not on the block size.
// Scratch buffers (per block: the compacted candidates and the block's lists) live in a pool
// that outlives the call, so steady-state calls allocate nothing and zero-fill nothing.
//
// Particles with a non-finite coordinate have no neighbors and are no one's neighbor (their
// distance is inf or NaN, which fails the test); boxes leave them out.
#include "seiche/neighbor/neighbor_list.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "seiche/simd/batch.hpp"
#include "seiche/simd/intrinsics.hpp"

namespace seiche::neighbor {
namespace {

using Batch = xsimd::batch<float, simd::Arch256>;  // 8 lanes in an AVX-512 build (batch.hpp)
using Ints = xsimd::batch<std::uint32_t, simd::Arch256>;
constexpr std::size_t W = Batch::size;
constexpr std::size_t kWaveBlocks = 32;  // blocks per wave: bounds the scratch lists
constexpr float kInf = std::numeric_limits<float>::infinity();

// Growable array without value-initialisation (new T[] of a trivial type leaves it as is); the
// first `keep` entries survive growth.
template <class T>
struct Buf {
  std::unique_ptr<T[]> p;
  std::size_t cap = 0;
  T* data() { return p.get(); }
  void ensure(std::size_t need, std::size_t keep) {
    if (need <= cap) return;
    const std::size_t c = std::max(need, cap + cap / 2);
    std::unique_ptr<T[]> q(new T[c]);
    if (keep) std::memcpy(q.get(), p.get(), keep * sizeof(T));
    p = std::move(q);
    cap = c;
  }
  std::size_t bytes() const { return cap * sizeof(T); }
};

struct Block {
  Buf<float> cx, cy, cz;  // compacted candidates of the current group
  Buf<std::uint32_t> cj;
  Buf<std::uint32_t> lists;  // the block's lists, back to back
  std::size_t used = 0;
  std::size_t bytes() const { return cx.bytes() * 3 + cj.bytes() + lists.bytes(); }
};

// Pool of per-call scratch: a call takes one (or makes one), returns it at the end. Safe with
// concurrent or nested calls; steady state reuses the same buffers.
struct Scratch {
  Block blocks[kWaveBlocks];
};
std::mutex pool_mutex;
std::vector<std::unique_ptr<Scratch>> pool;

std::unique_ptr<Scratch> take_scratch() {
  std::lock_guard lock(pool_mutex);
  if (pool.empty()) return std::make_unique<Scratch>();
  auto s = std::move(pool.back());
  pool.pop_back();
  return s;
}
void give_back(std::unique_ptr<Scratch> s) {
  std::lock_guard lock(pool_mutex);
  pool.push_back(std::move(s));
}

struct Ctx {
  const CellGrid* grid;
  const float* p[3];
  std::size_t n;
  float r2;
  std::int32_t reach;
  std::uint32_t* counts;  // count of sorted particle i goes to counts[i]
};

inline bool finite3(const float* const p[3], std::size_t i) {
  return std::isfinite(p[0][i]) && std::isfinite(p[1][i]) && std::isfinite(p[2][i]);
}

// Compacted candidates: x, y, z and sorted index j.
struct CandOut {
  float* x;
  float* y;
  float* z;
  std::uint32_t* j;
};

// Appends the candidates of [b, e) whose squared gap to the box is < r2 to o (room for e - b + W
// past cnt is there). kSafe: every load of W from b..e stays < n.
template <bool kSafe>
[[gnu::always_inline]] inline std::uint32_t compact_range(const float* const p[3], std::size_t n, const Batch lo[3],
                            const Batch hi[3], const Batch& rr, std::uint32_t b, std::uint32_t e,
                            const CandOut o, std::uint32_t cnt) {
  // Local copies: the stores below could alias anything reached through a pointer.
  const Batch zero(0.0f), r2 = rr, l[3] = {lo[0], lo[1], lo[2]}, h[3] = {hi[0], hi[1], hi[2]};
  const float* const q[3] = {p[0], p[1], p[2]};
  float* const ox = o.x;
  float* const oy = o.y;
  float* const oz = o.z;
  std::uint32_t* const oj = o.j;
  const Ints step = Ints(std::uint32_t(W));
  Ints j = Ints(b) + simd::lane_index<simd::Arch256>();  // the sorted indices of the W candidates
  for (std::uint32_t k = b; k < e; k += std::uint32_t(W), j += step) {
    Batch c[3];
    if (kSafe) {
      for (int a = 0; a < 3; ++a) c[a] = Batch::load_unaligned(q[a] + k);
    } else {  // the last particles of the arrays: never read past n
      alignas(64) float t[3][W];
      for (int a = 0; a < 3; ++a)
        for (std::size_t ln = 0; ln < W; ++ln) t[a][ln] = k + ln < n ? q[a][k + ln] : kInf;
      for (int a = 0; a < 3; ++a) c[a] = Batch::load_aligned(t[a]);
    }
    Batch g[3];
    for (int a = 0; a < 3; ++a) g[a] = xsimd::max(xsimd::max(l[a] - c[a], c[a] - h[a]), zero);
    std::uint32_t bits = simd::lane_bits(g[0] * g[0] + g[1] * g[1] + g[2] * g[2] < r2);
    if (e - k < W) bits &= (1u << (e - k)) - 1;
    const auto pack = simd::left_pack<simd::Arch256>(bits);
    pack.store(ox + cnt, c[0]);
    pack.store(oy + cnt, c[1]);
    pack.store(oz + cnt, c[2]);
    pack.store(oj + cnt, j);
    cnt += std::uint32_t(std::popcount(bits));
  }
  return cnt;
}

[[gnu::noinline]] std::uint32_t compact_tail(const float* const p[3], std::size_t n, const Batch lo[3],
                                             const Batch hi[3], const Batch& rr, std::uint32_t b,
                                             std::uint32_t e, const CandOut o, std::uint32_t cnt) {
  return compact_range<false>(p, n, lo, hi, rr, b, e, o, cnt);
}

// compact_range over rows [rb[r], re[r]) for r < rows, in order (one call per group: the set-up
// of the SIMD constants is paid once). Rows that end near n take the slow, bounded loads.
[[gnu::noinline]] std::uint32_t compact_rows(const float* const p[3], std::size_t n, const Batch lo[3],
                                             const Batch hi[3], const Batch& rr, const std::uint32_t* rb,
                                             const std::uint32_t* re, int rows, const CandOut o,
                                             std::uint32_t cnt) {
  for (int r = 0; r < rows; ++r)
    cnt = std::size_t(re[r]) + W - 1 <= n ? compact_range<true>(p, n, lo, hi, rr, rb[r], re[r], o, cnt)
                                          : compact_tail(p, n, lo, hi, rr, rb[r], re[r], o, cnt);
  return cnt;
}

// Compacted candidates, padded to a multiple of W.
struct Cand {
  const float *x, *y, *z;
  const std::uint32_t* j;
  std::uint32_t padded;
};

// The neighbors of finite particle i among the candidates, to out (room for padded + W).
inline std::uint32_t query1(const Cand& c, const float* const p[3], std::uint32_t i, const Batch& rr,
                            std::uint32_t* out) {
  const Batch qx(p[0][i]), qy(p[1][i]), qz(p[2][i]), r2 = rr;
  // Local copies: the stores to out could alias anything reached through a pointer.
  const float* const cx = c.x;
  const float* const cy = c.y;
  const float* const cz = c.z;
  const std::uint32_t* const cj = c.j;
  const std::uint32_t padded = c.padded;
  std::uint32_t count = 0;
  const Ints self(i);
  for (std::uint32_t k = 0; k < padded; k += std::uint32_t(W)) {
    const Batch dx = qx - Batch::load_unaligned(cx + k);
    const Batch dy = qy - Batch::load_unaligned(cy + k);
    const Batch dz = qz - Batch::load_unaligned(cz + k);
    const Ints j = Ints::load_unaligned(cj + k);
    const std::uint32_t bits =
        simd::lane_bits(dx * dx + dy * dy + dz * dz < r2) & ~simd::lane_bits(j == self);
    simd::left_pack<simd::Arch256>(bits).store(out + count, j);
    count += std::uint32_t(std::popcount(bits));
  }
  return count;
}

// Lists of the sorted particles [g0, g1), all in cell c.
void process_group(const Ctx& ctx, Block& blk, const std::int32_t c[3], std::uint32_t g0,
                   std::uint32_t g1) {
  const float* const* p = ctx.p;
  // A box around the group's finite particles. The plain min/max pass ignores NaN (comparisons
  // fail) and is exact when every coordinate is finite; an infinite one shows in the box, and
  // then the box is redone over the finite particles only. (A box larger than needed is fine.)
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    float l = kInf, h = -kInf;
    for (std::uint32_t i = g0; i < g1; ++i) {
      const float v = p[a][i];
      l = v < l ? v : l;
      h = v > h ? v : h;
    }
    lo[a] = l, hi[a] = h;
  }
  if (!(std::isfinite(lo[0]) && std::isfinite(lo[1]) && std::isfinite(lo[2]) && std::isfinite(hi[0]) &&
        std::isfinite(hi[1]) && std::isfinite(hi[2]))) {
    bool any = false;
    for (int a = 0; a < 3; ++a) lo[a] = kInf, hi[a] = -kInf;
    for (std::uint32_t i = g0; i < g1; ++i) {
      if (!finite3(p, i)) continue;
      any = true;
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a][i]), hi[a] = std::max(hi[a], p[a][i]);
    }
    if (!any) {
      std::fill(ctx.counts + g0, ctx.counts + g1, 0u);
      return;
    }
  }
  const Batch blo[3] = {Batch(lo[0]), Batch(lo[1]), Batch(lo[2])};
  const Batch bhi[3] = {Batch(hi[0]), Batch(hi[1]), Batch(hi[2])};
  const Batch rr(ctx.r2);

  // Rows: x range [x0, x1) of cells, rows (yy, zz) in [y0, y1] x [z0, z1].
  const CellGrid& g = *ctx.grid;
  const std::int32_t* d = g.spec().dims;
  const std::int32_t R = ctx.reach;
  const std::uint32_t x0 = std::uint32_t(std::clamp(c[0] - R, 0, d[0]));
  const std::uint32_t x1 = std::uint32_t(std::clamp(c[0] + R + 1, 0, d[0]));
  const std::int32_t y0 = std::max(c[1] - R, 0), y1 = std::min(c[1] + R, d[1] - 1);
  const std::int32_t z0 = std::max(c[2] - R, 0), z1 = std::min(c[2] + R, d[2] - 1);
  std::size_t total = 0;  // all row candidates: a bound on the compacted count
  for (std::int32_t zz = z0; zz <= z1; ++zz)
    for (std::int32_t yy = y0; yy <= y1; ++yy) {
      const std::uint32_t row_key = g.cell_index(0, yy, zz);
      total += g.cell_begin(row_key + x1) - g.cell_begin(row_key + x0);
    }
  const std::size_t room = total + 2 * W;
  blk.cx.ensure(room, 0), blk.cy.ensure(room, 0), blk.cz.ensure(room, 0), blk.cj.ensure(room, 0);
  const CandOut o{blk.cx.data(), blk.cy.data(), blk.cz.data(), blk.cj.data()};

  // Compacted candidates, rows in increasing (zz, yy), so in increasing sorted index; the rows
  // go to compact_rows 9 at a time (all of them when reach = 1).
  std::uint32_t cnt = 0, rb[9], re[9];
  int rows = 0;
  for (std::int32_t zz = z0; zz <= z1; ++zz)
    for (std::int32_t yy = y0; yy <= y1; ++yy) {
      const std::uint32_t row_key = g.cell_index(0, yy, zz);
      const std::uint32_t b = g.cell_begin(row_key + x0), e = g.cell_begin(row_key + x1);
      if (b >= e) continue;
      rb[rows] = b, re[rows] = e;
      if (++rows == 9) cnt = compact_rows(p, ctx.n, blo, bhi, rr, rb, re, rows, o, cnt), rows = 0;
    }
  if (rows > 0) cnt = compact_rows(p, ctx.n, blo, bhi, rr, rb, re, rows, o, cnt);
  // Pad to a multiple of W with candidates that fail every test.
  const std::uint32_t padded = std::uint32_t((cnt + W - 1) / W * W);
  const Batch inf(kInf);
  inf.store_unaligned(o.x + cnt), inf.store_unaligned(o.y + cnt), inf.store_unaligned(o.z + cnt);
  std::fill_n(o.j + cnt, W, 0u);

  // Room for every list of the group (each at most padded - 1, plus W of junk past the last).
  blk.lists.ensure(blk.used + std::size_t(g1 - g0) * padded + W, blk.used);
  const Cand cand{o.x, o.y, o.z, o.j, padded};
  for (std::uint32_t i = g0; i < g1; ++i) {
    if (!finite3(p, i)) {
      ctx.counts[i] = 0;
      continue;
    }
    const std::uint32_t count = query1(cand, p, i, rr, blk.lists.data() + blk.used);
    blk.used += count;
    ctx.counts[i] = count;
  }
}

// Lists of the sorted particles [b0, b1) into blk (from blk.used = 0).
void process_block(const Ctx& ctx, Block& blk, std::uint32_t b0, std::uint32_t b1) {
  blk.used = 0;
  const CellGrid& g = *ctx.grid;
  for (std::uint32_t i = b0; i < b1;) {
    std::int32_t c[3];
    g.cell_of(ctx.p[0][i], ctx.p[1][i], ctx.p[2][i], c);
    const std::uint32_t cell = g.cell_index(c[0], c[1], c[2]);
    const std::uint32_t cb = g.cell_begin(cell), ce = g.cell_end(cell);
    // The group: the rest of i's cell within the block (i alone if the positions are not the
    // ones the grid was built from, a broken precondition that must still not loop forever).
    const std::uint32_t g1 = cb <= i && i < ce ? std::min(ce, b1) : i + 1;
    process_group(ctx, blk, c, i, g1);
    i = g1;
  }
}

// dst[0, count) = src[0, count). `stream`: non-temporal stores, for lists far larger than the
// caches: they skip reading the destination lines in first (half the memory traffic).
void copy_list(const std::uint32_t* src, std::size_t count, std::uint32_t* dst, bool stream) {
  if (stream) simd::stream_copy<simd::Arch256>(dst, src, count);
  else std::copy_n(src, count, dst);
}

// Lets `v` hold `needed` entries, growing to `estimate` at once (not doubling) to keep memory
// close to the final size.
void make_room(std::vector<std::uint32_t>& v, std::size_t needed, std::size_t estimate) {
  if (needed > v.capacity()) v.reserve(std::max(needed, estimate));
}

}  // namespace

std::size_t neighbor_list_scratch_bytes() {
  std::lock_guard lock(pool_mutex);
  std::size_t total = 0;
  for (const auto& s : pool)
    for (const Block& b : s->blocks) total += b.bytes();
  return total;
}

std::size_t NeighborList::bytes() const {
  return (offsets.capacity() + indices.capacity()) * sizeof(std::uint32_t);
}

void build_neighbor_list(const CellGrid& grid, const float* x, const float* y, const float* z,
                         std::size_t n, float radius, NeighborList& out) {
  if (n != grid.order().size())
    throw std::invalid_argument("seiche::neighbor::build_neighbor_list: n differs from the grid's particle count");
  const std::size_t m = grid.num_in_grid();  // sorted [0, m) are in cells; the rest have no list
  if (!(radius > 0) || m == 0) {
    out.offsets.assign(n + 1, 0);
    out.indices.clear();  // keeps its storage for reuse
    return;
  }
  out.offsets.resize(n + 1);  // every entry is written below
  out.offsets[0] = 0;

  // How many cells away a neighbor can be: 1 when radius <= cell_size, the usual case.
  const std::int32_t* d = grid.spec().dims;
  const double cells_away = std::ceil(double(radius) / double(grid.spec().cell_size));
  const auto reach = std::int32_t(std::clamp(std::isnan(cells_away) ? 1.0 : cells_away, 1.0,
                                             double(std::max({d[0], d[1], d[2]}))));
  const Ctx ctx{&grid, {x, y, z}, n, radius * radius, reach, out.offsets.data() + 1};

  // Block size: small inputs get small blocks so that every core has work (the result does not
  // depend on it).
  const std::size_t grain = std::clamp<std::size_t>((m + kWaveBlocks - 1) / kWaveBlocks, 128, 1024);
  const std::size_t wave = kWaveBlocks * grain;
  std::unique_ptr<Scratch> scratch = take_scratch();
  Block* const blocks = scratch->blocks;
  std::size_t total = 0;  // entries placed so far (out.indices[0, total) are final)
  try {
    for (std::size_t w0 = 0; w0 < m; w0 += wave) {
      const std::size_t w1 = std::min(m, w0 + wave);
      const std::size_t nblocks = (w1 - w0 + grain - 1) / grain;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks, 1), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
          const std::size_t b0 = w0 + b * grain;
          process_block(ctx, blocks[b], std::uint32_t(b0), std::uint32_t(std::min(w1, b0 + grain)));
        }
      });
      // Offsets of the wave, in order, then the blocks' lists copied into place.
      std::uint64_t sum = total;
      std::uint32_t* const off = out.offsets.data();
      for (std::size_t i = w0; i < w1; ++i) off[i + 1] = std::uint32_t(sum += off[i + 1]);
      if (sum > std::numeric_limits<std::uint32_t>::max())
        throw std::length_error("seiche::neighbor::build_neighbor_list: more than 2^32-1 neighbor entries");
      if (out.indices.size() < sum) {  // grows only: a steady-state call never zero-fills
        make_room(out.indices, sum, std::size_t(double(sum) / double(w1) * double(m) * 1.0625));
        out.indices.resize(sum);
      }
      // Lists of more than ~16 MB do not stay in the caches anyway: stream them out.
      const bool stream = double(sum) / double(w1) * double(m) * sizeof(std::uint32_t) > 16e6;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks, 1), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b)
          copy_list(blocks[b].lists.data(), blocks[b].used, out.indices.data() + off[w0 + b * grain], stream);
      });
      total = sum;
    }
  } catch (...) {
    give_back(std::move(scratch));
    throw;
  }
  give_back(std::move(scratch));
  out.indices.resize(total);
  std::fill(out.offsets.begin() + std::ptrdiff_t(m) + 1, out.offsets.end(), std::uint32_t(total));
  if (out.indices.capacity() - out.indices.size() > out.indices.size() / 8) out.indices.shrink_to_fit();
}

}  // namespace seiche::neighbor
