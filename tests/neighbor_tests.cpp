// Neighbor layer against brute force: the grid order must be the stable sort of the particles by
// cell key (the unique deterministic answer), cell ranges must agree with cell_of, and each
// neighbor list must equal the all-pairs list computed with the same float expression, exactly
// and in increasing order. Clouds: random, dense lattice, one cell, negative, huge and
// non-finite coordinates, excluded particles, empty; 1 vs 2 threads must give identical output.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <thread>
#include <vector>

#include <tbb/global_control.h>

#include "seiche/neighbor/cell_grid.hpp"
#include "seiche/neighbor/neighbor_list.hpp"

namespace {

namespace nb = seiche::neighbor;

struct Cloud {
  std::vector<float> x, y, z;
  std::vector<std::uint8_t> in_grid;  // empty: all in the grid
  std::size_t size() const { return x.size(); }
  void add(float px, float py, float pz) { x.push_back(px), y.push_back(py), z.push_back(pz); }
};

struct Result {
  nb::CellGrid grid;
  Cloud sorted;  // the cloud after applying grid.order()
  nb::NeighborList list;
};

Result run(const Cloud& c, const nb::GridSpec& spec, float radius) {
  Result r;
  const std::size_t n = c.size();
  r.grid.build(spec, c.x.data(), c.y.data(), c.z.data(), c.in_grid.empty() ? nullptr : c.in_grid.data(), n);
  for (std::uint32_t k : r.grid.order()) {
    r.sorted.add(c.x[k], c.y[k], c.z[k]);
    if (!c.in_grid.empty()) r.sorted.in_grid.push_back(c.in_grid[k]);
  }
  nb::build_neighbor_list(r.grid, r.sorted.x.data(), r.sorted.y.data(), r.sorted.z.data(), n, radius, r.list);
  return r;
}

std::uint32_t key_of(const nb::CellGrid& g, float x, float y, float z) {
  std::int32_t c[3];
  g.cell_of(x, y, z, c);
  return g.cell_index(c[0], c[1], c[2]);
}

// Checks every property against the oracles; returns the total number of neighbor entries.
// Lists are compared for every `stride`-th particle (all-pairs is quadratic).
std::size_t check(const Cloud& c, const nb::GridSpec& spec, float radius, std::size_t stride = 1) {
  const Result r = run(c, spec, radius);
  const std::size_t n = c.size();
  const nb::CellGrid& g = r.grid;
  const auto in = [&](std::size_t i) { return c.in_grid.empty() || c.in_grid[i] != 0; };

  // Order: the stable sort by key, excluded particles last.
  const std::uint32_t outside = std::uint32_t(g.spec().cell_count());
  std::vector<std::uint32_t> key(n), expect(n);
  for (std::size_t i = 0; i < n; ++i) key[i] = in(i) ? key_of(g, c.x[i], c.y[i], c.z[i]) : outside;
  std::iota(expect.begin(), expect.end(), 0u);
  std::stable_sort(expect.begin(), expect.end(), [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
  EXPECT_TRUE(std::equal(expect.begin(), expect.end(), g.order().begin(), g.order().end()));
  const std::size_t m = std::size_t(std::count_if(key.begin(), key.end(), [&](std::uint32_t k) { return k != outside; }));
  EXPECT_EQ(g.num_in_grid(), m);

  // Cells: contiguous, consistent with cell_of, covering [0, m).
  EXPECT_EQ(g.cell_begin(0), 0u);
  for (std::uint32_t cell = 0; cell < outside; ++cell) EXPECT_LE(g.cell_begin(cell), g.cell_end(cell));
  EXPECT_EQ(g.cell_end(outside - 1), m);
  for (std::size_t k = 0; k < m; ++k) {
    const std::uint32_t cell = key_of(g, r.sorted.x[k], r.sorted.y[k], r.sorted.z[k]);
    EXPECT_LE(g.cell_begin(cell), k);
    EXPECT_LT(k, g.cell_end(cell));
  }

  // Lists: exactly the brute-force set, increasing, none for excluded particles.
  const float r2 = radius * radius;
  EXPECT_EQ(r.list.size(), n);
  EXPECT_EQ(r.list.offsets.front(), 0u);
  EXPECT_EQ(r.list.offsets.back(), r.list.indices.size());
  std::vector<std::uint32_t> want;
  for (std::size_t i = 0; i < n; i += stride) {
    want.clear();
    if (i < m)
      for (std::size_t j = 0; j < m; ++j) {
        const float dx = r.sorted.x[i] - r.sorted.x[j], dy = r.sorted.y[i] - r.sorted.y[j],
                    dz = r.sorted.z[i] - r.sorted.z[j];
        if (j != i && dx * dx + dy * dy + dz * dz < r2) want.push_back(std::uint32_t(j));
      }
    const std::vector<std::uint32_t> got(r.list.indices.begin() + r.list.offsets[i],
                                         r.list.indices.begin() + r.list.offsets[i + 1]);
    EXPECT_EQ(got, want) << "particle " << i << " at (" << r.sorted.x[i] << ", " << r.sorted.y[i]
                         << ", " << r.sorted.z[i] << ")";
    if (got != want) break;  // one report is enough
  }
  return r.list.indices.size();
}

Cloud random_cloud(std::size_t n, float lo, float hi, unsigned seed) {
  Cloud c;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  for (std::size_t i = 0; i < n; ++i) c.add(u(rng), u(rng), u(rng));
  return c;
}

nb::GridSpec spec_for(float lo, float hi, float cell) {
  const float a[3] = {lo, lo, lo}, b[3] = {hi, hi, hi};
  return nb::make_grid_spec(a, b, cell);
}

TEST(GridSpec, DimsCoverTheBoxWithCellsAtLeastRequested) {
  const float lo[3] = {-1, 0, 2}, hi[3] = {1, 0.35f, 2};
  const nb::GridSpec s = nb::make_grid_spec(lo, hi, 0.1f);
  EXPECT_GE(s.cell_size, 0.1f);
  EXPECT_LT(s.cell_size, 0.1f * 1.001f);
  EXPECT_EQ(s.dims[0], 20);
  EXPECT_EQ(s.dims[1], 4);
  EXPECT_EQ(s.dims[2], 1);  // zero extent
  for (int a = 0; a < 3; ++a) EXPECT_EQ(s.origin[a], lo[a]);
}

TEST(GridSpec, GrowsCellsToRespectMaxCells) {
  const float lo[3] = {0, 0, 0}, hi[3] = {10, 10, 10};
  const nb::GridSpec s = nb::make_grid_spec(lo, hi, 0.01f, 1000);
  EXPECT_LE(s.cell_count(), 1000u);
  EXPECT_GE(s.cell_count(), 500u);  // not grown more than needed
  EXPECT_GE(s.cell_size, 1.0f);
}

TEST(GridSpec, DegenerateInputsGiveAUsableGrid) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float lo[3] = {nan, 5, -inf}, hi[3] = {1, -5, inf};
  for (float cell : {0.0f, -1.0f, nan, 0.5f}) {
    const nb::GridSpec s = nb::make_grid_spec(lo, hi, cell, 4096);
    EXPECT_GT(s.cell_size, 0.0f);
    EXPECT_LE(s.cell_count(), 4096u);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(s.dims[a], 1);
      EXPECT_TRUE(std::isfinite(s.origin[a]));
    }
    EXPECT_EQ(s.origin[1], -5.0f);  // swapped min and max
    EXPECT_EQ(s.dims[1], s.cell_size <= 10.0f ? int(std::ceil(10.0f / s.cell_size)) : 1);
  }
}

TEST(CellGrid, CellOfClampsOutsideAndNonFiniteCoordinates) {
  nb::CellGrid g;
  g.build(spec_for(0, 1, 0.25f), nullptr, nullptr, nullptr, nullptr, 0);
  std::int32_t c[3];
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  g.cell_of(nan, -inf, inf, c);
  EXPECT_EQ(c[0], 0);
  EXPECT_EQ(c[1], 0);
  EXPECT_EQ(c[2], 3);
  g.cell_of(-1e30f, 0.3f, 1e30f, c);
  EXPECT_EQ(c[0], 0);
  EXPECT_EQ(c[1], 1);
  EXPECT_EQ(c[2], 3);
}

TEST(Neighbors, RandomClouds) {
  for (auto [n, seed] : {std::pair<std::size_t, unsigned>{1, 1}, {7, 2}, {100, 3}, {2000, 4}, {5000, 5}}) {
    const Cloud c = random_cloud(n, 0.0f, 1.0f, seed);
    const std::size_t total = check(c, spec_for(0, 1, 0.1f), 0.1f);
    if (n >= 2000) {
      EXPECT_GT(total, n);  // the test is not vacuous
    }
  }
}

TEST(Neighbors, LargeCloudAcrossWorkBlocks) {
  // More particles than one wave of blocks: lists of blocks and waves must join up exactly.
  const Cloud c = random_cloud(90000, 0.0f, 3.0f, 15);
  EXPECT_GT(check(c, spec_for(0, 3, 0.08f), 0.08f, 53), c.size());
}

TEST(Neighbors, RadiusSmallerOrLargerThanCells) {
  const Cloud c = random_cloud(3000, 0.0f, 1.0f, 11);
  EXPECT_GT(check(c, spec_for(0, 1, 0.1f), 0.04f), 0u);
  EXPECT_GT(check(c, spec_for(0, 1, 0.05f), 0.12f), 0u);  // reaches 3 cells away
}

TEST(Neighbors, DenseJitteredBlockHasLatticeNeighborCounts) {
  Cloud c;
  const float s = 0.05f;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(-0.01f * s, 0.01f * s);
  const int side = 14;
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i)
        c.add((i + 0.5f) * s + jitter(rng), (j + 0.5f) * s + jitter(rng), (k + 0.5f) * s + jitter(rng));
  const std::size_t total = check(c, spec_for(0, side * s, 2 * s), 2 * s);
  // Interior particles have 26 lattice neighbours closer than 2s, plus part of the 6 at 2s.
  EXPECT_GT(double(total) / double(c.size()), 15.0);
  EXPECT_LT(double(total) / double(c.size()), 32.0);
}

TEST(Neighbors, AllParticlesInOneCell) {
  const Cloud c = random_cloud(300, 0.40f, 0.45f, 6);
  EXPECT_EQ(check(c, spec_for(0, 1, 0.5f), 0.5f), 300u * 299u);  // everyone sees everyone
}

TEST(Neighbors, CoincidentParticlesAreNeighbors) {
  Cloud c;
  for (int i = 0; i < 20; ++i) c.add(0.5f, 0.5f, 0.5f);
  EXPECT_EQ(check(c, spec_for(0, 1, 0.1f), 0.1f), 20u * 19u);
}

TEST(Neighbors, NegativeCoordinates) {
  const Cloud c = random_cloud(3000, -3.0f, -2.0f, 7);
  EXPECT_GT(check(c, spec_for(-3, -2, 0.1f), 0.1f), 0u);
}

TEST(Neighbors, LargeCoordinates) {
  // Near 1e6 floats are 1/16 apart: the grid must still be exact.
  Cloud c = random_cloud(3000, 1.0e6f, 1.0e6f + 20.0f, 8);
  EXPECT_GT(check(c, spec_for(1.0e6f, 1.0e6f + 20.0f, 0.7f), 0.7f), 0u);
}

TEST(Neighbors, ParticlesFarOutsideTheBoxAndNonFinite) {
  Cloud c = random_cloud(2000, 0.0f, 1.0f, 9);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  // Clusters far outside: they clamp into border cells and must still find each other.
  for (float f : {1.0e6f, -1.0e6f})
    for (int i = 0; i < 5; ++i) {
      c.add(f + float(i), 0.5f, 0.5f);
      c.add(f + float(i), 0.5f, 0.55f);
      c.add(0.3f, f, f + 0.0625f * float(i));
    }
  c.add(nan, 0.5f, 0.5f);
  c.add(0.5f, nan, nan);
  c.add(inf, 0.5f, 0.5f);
  c.add(-inf, -inf, 0.5f);
  c.add(0.5f, 0.5f, 0.5f);  // a normal particle near the non-finite ones
  EXPECT_GT(check(c, spec_for(0, 1, 0.1f), 0.1f), 0u);
}

TEST(Neighbors, EmptyInput) {
  const Cloud c;
  const Result r = run(c, spec_for(0, 1, 0.1f), 0.1f);
  EXPECT_TRUE(r.grid.order().empty());
  EXPECT_EQ(r.grid.num_in_grid(), 0u);
  EXPECT_EQ(r.grid.cell_end(r.grid.cell_index(9, 9, 9)), 0u);
  EXPECT_EQ(r.list.size(), 0u);
  EXPECT_EQ(r.list.offsets.size(), 1u);
  EXPECT_TRUE(r.list.indices.empty());
}

TEST(Neighbors, ExcludedParticlesGoLastInInputOrderWithNoNeighbors) {
  Cloud c = random_cloud(3000, 0.0f, 1.0f, 10);
  c.in_grid.resize(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) c.in_grid[i] = i % 3 != 0;
  EXPECT_GT(check(c, spec_for(0, 1, 0.1f), 0.1f), 0u);
  const Result r = run(c, spec_for(0, 1, 0.1f), 0.1f);
  const std::size_t m = r.grid.num_in_grid();
  EXPECT_EQ(m, 2000u);
  for (std::size_t k = m; k < c.size(); ++k) EXPECT_EQ(r.grid.order()[k], 3 * (k - m));
}

TEST(Neighbors, SortedInputKeepsItsOrder) {
  // Building on already sorted positions (the usual simulation step) gives the identity.
  const Cloud c = random_cloud(4000, 0.0f, 1.0f, 12);
  const Result first = run(c, spec_for(0, 1, 0.1f), 0.1f);
  const Result second = run(first.sorted, spec_for(0, 1, 0.1f), 0.1f);
  for (std::size_t k = 0; k < c.size(); ++k) ASSERT_EQ(second.grid.order()[k], k);
  EXPECT_EQ(second.list.offsets, first.list.offsets);
  EXPECT_EQ(second.list.indices, first.list.indices);
}

TEST(Neighbors, MemoryIsTight) {
  const Cloud c = random_cloud(20000, 0.0f, 1.0f, 13);
  const Result r = run(c, spec_for(0, 1, 0.05f), 0.05f);
  EXPECT_LE(r.list.indices.capacity(), r.list.indices.size() + r.list.indices.size() / 8);
  EXPECT_EQ(r.list.offsets.capacity(), c.size() + 1);
}

TEST(Neighbors, RepeatedCallsReuseBuffersExactly) {
  // Lists and scratch keep their storage across calls: a call after a larger or a smaller one,
  // into the same objects, must give exactly what a fresh call gives.
  const Cloud big = random_cloud(30000, 0.0f, 1.5f, 16), small = random_cloud(1500, 0.0f, 1.0f, 17);
  const nb::GridSpec big_spec = spec_for(0, 1.5f, 0.06f), small_spec = spec_for(0, 1, 0.1f);
  const Result fresh_big = run(big, big_spec, 0.06f), fresh_small = run(small, small_spec, 0.1f);
  nb::CellGrid grid;
  nb::NeighborList list;
  for (int round = 0; round < 2; ++round)
    for (const auto* c : {&big, &small, &big}) {
      const bool is_big = c == &big;
      const Result& fresh = is_big ? fresh_big : fresh_small;
      grid.build(is_big ? big_spec : small_spec, c->x.data(), c->y.data(), c->z.data(), nullptr, c->size());
      nb::build_neighbor_list(grid, fresh.sorted.x.data(), fresh.sorted.y.data(), fresh.sorted.z.data(),
                              c->size(), is_big ? 0.06f : 0.1f, list);
      EXPECT_EQ(list.offsets, fresh.list.offsets);
      EXPECT_EQ(list.indices, fresh.list.indices);
    }
}

TEST(Neighbors, ConcurrentCallsFromTwoThreads) {
  // Independent searches may run at the same time (scratch is per call).
  const Cloud a = random_cloud(20000, 0.0f, 1.0f, 18), b = random_cloud(12000, -1.0f, 0.0f, 19);
  const Result ra = run(a, spec_for(0, 1, 0.07f), 0.07f), rb = run(b, spec_for(-1, 0, 0.09f), 0.09f);
  Result ca, cb;
  std::thread t([&] { for (int k = 0; k < 5; ++k) ca = run(a, spec_for(0, 1, 0.07f), 0.07f); });
  for (int k = 0; k < 5; ++k) cb = run(b, spec_for(-1, 0, 0.09f), 0.09f);
  t.join();
  EXPECT_EQ(ca.list.indices, ra.list.indices);
  EXPECT_EQ(cb.list.indices, rb.list.indices);
  EXPECT_EQ(ca.list.offsets, ra.list.offsets);
  EXPECT_EQ(cb.list.offsets, rb.list.offsets);
}

TEST(Determinism, OneAndTwoThreadsGiveIdenticalResults) {
  Cloud c = random_cloud(60000, 0.0f, 2.0f, 14);  // shuffled input: the atomic counting sort path
  c.in_grid.assign(c.size(), 1);
  for (std::size_t i = 0; i < c.size(); i += 97) c.in_grid[i] = 0;
  auto at = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    return run(c, spec_for(0, 2, 0.05f), 0.05f);
  };
  const Result one = at(1), two = at(2);
  EXPECT_TRUE(std::equal(one.grid.order().begin(), one.grid.order().end(), two.grid.order().begin(), two.grid.order().end()));
  EXPECT_EQ(one.list.offsets, two.list.offsets);
  EXPECT_EQ(one.list.indices, two.list.indices);
  EXPECT_GT(one.list.indices.size(), c.size());
}

}  // namespace
