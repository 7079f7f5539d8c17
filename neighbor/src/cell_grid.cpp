// Uniform grid, built like a GPU counting sort.
//
// 1. key per particle: the clamped cell (cz * ny + cy) * nx + cx, or `cell_count` (one bucket
//    after every cell) for particles outside the grid. Cell coordinates are computed in double,
//    so their rounding error is far below the margin make_grid_spec puts on the cell size: two
//    particles closer than the query radius never land two cells apart.
// 2. If the keys are already non-decreasing (the caller applied last step's order and nothing
//    crossed a cell), the order is the identity and cell starts are read off the key changes.
// 3. Otherwise: integer atomic counts per bucket, exclusive scan, scatter with an atomic cursor,
//    then each bucket's few entries sorted by input index. Atomics make the scatter order
//    thread-dependent, the final per-bucket sort removes that: the result is the stable sort of
//    the input by key, whatever the thread count.
#include "seiche/neighbor/cell_grid.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "prefix_sum.hpp"

namespace seiche::neighbor {
namespace {

constexpr std::size_t kBlock = 4096;  // particles per task: big enough to amortise scheduling

struct Axis {
  double origin, inv_cell;
  double last;  // dims - 1
};

// Clamped cell coordinate along one axis. Written as selects so the key loop vectorises;
// `t >= 0` is false for NaN, which therefore goes to cell 0.
inline std::int32_t axis_cell(float p, const Axis& a) {
  double t = (double(p) - a.origin) * a.inv_cell;
  t = t >= 0.0 ? t : 0.0;
  t = t < a.last ? t : a.last;
  return std::int32_t(t);
}

struct Axes {
  Axis a[3];
  std::uint32_t nx, ny;
};

Axes axes_of(const GridSpec& s) {
  Axes r{};
  for (int k = 0; k < 3; ++k)
    r.a[k] = {double(s.origin[k]), 1.0 / double(s.cell_size), double(s.dims[k] - 1)};
  r.nx = std::uint32_t(s.dims[0]);
  r.ny = std::uint32_t(s.dims[1]);
  return r;
}

inline std::uint32_t key_of(const Axes& g, float x, float y, float z) {
  const auto cx = std::uint32_t(axis_cell(x, g.a[0]));
  const auto cy = std::uint32_t(axis_cell(y, g.a[1]));
  const auto cz = std::uint32_t(axis_cell(z, g.a[2]));
  return (cz * g.ny + cy) * g.nx + cx;
}

// Number of cells when each axis of extent ext[k] is cut into cells of size c (as a double, so
// absurd ratios cannot overflow).
double cells_for(const double ext[3], double c) {
  double p = 1;
  for (int k = 0; k < 3; ++k) p *= std::max(1.0, std::ceil(ext[k] / c));
  return p;
}

}  // namespace

GridSpec make_grid_spec(const float box_min[3], const float box_max[3], float min_cell_size,
                        std::size_t max_cells) {
  // Keys and cell starts are 32-bit: keep cell_count + 2 buckets well inside that.
  const double cap = double(std::clamp<std::size_t>(max_cells, 1, std::size_t(1) << 31));
  GridSpec s;
  double lo[3], ext[3];
  for (int k = 0; k < 3; ++k) {
    double a = box_min[k], b = box_max[k];
    if (!std::isfinite(a)) a = std::isfinite(b) ? b : 0.0;
    if (!std::isfinite(b)) b = a;
    if (b < a) std::swap(a, b);
    lo[k] = a;
    ext[k] = b - a;
  }
  // A non-positive or NaN request means "as fine as max_cells allows".
  double cell = min_cell_size > 0 ? double(min_cell_size) : double(std::numeric_limits<float>::min());
  if (cells_for(ext, cell) > cap) {
    // Smallest cell size that fits (the count only falls as the cell grows): bisection.
    double hi = std::max({ext[0], ext[1], ext[2]});  // one cell per axis always fits
    for (int it = 0; it < 200 && hi > cell * (1 + 1e-12); ++it) {
      const double mid = 0.5 * (cell + hi);
      (cells_for(ext, mid) > cap ? cell : hi) = mid;
    }
    cell = hi;
  }
  // Margin of 2^-19: a pair that passes the float test |d|^2 < r^2 with r = min_cell_size may be
  // up to a few float ulps farther apart than r; the margin keeps such pairs within one cell.
  const float c = std::nextafter(float(cell * (1.0 + 0x1p-19)), std::numeric_limits<float>::infinity());
  s.cell_size = c;
  for (int k = 0; k < 3; ++k) {
    s.origin[k] = float(lo[k]);
    s.dims[k] = std::int32_t(std::max(1.0, std::ceil(ext[k] / double(c))));
  }
  return s;
}

void CellGrid::cell_of(float x, float y, float z, std::int32_t out[3]) const {
  const Axes g = axes_of(spec_);
  out[0] = axis_cell(x, g.a[0]);
  out[1] = axis_cell(y, g.a[1]);
  out[2] = axis_cell(z, g.a[2]);
}

void CellGrid::build(const GridSpec& spec, const float* x, const float* y, const float* z,
                     const std::uint8_t* in_grid, std::size_t n) {
  spec_ = spec;
  for (auto& d : spec_.dims) d = std::max<std::int32_t>(d, 1);
  const std::size_t cells = spec_.cell_count();
  if (n >= std::numeric_limits<std::uint32_t>::max() ||
      cells + 2 >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("seiche::neighbor::CellGrid::build: particle or cell count exceeds 32-bit indices");

  const auto outside = std::uint32_t(cells);  // bucket for in_grid == 0, after every cell
  keys_.resize(n);
  order_.resize(n);
  cell_start_.resize(cells + 2);  // buckets 0..cells, plus the end
  std::uint32_t* key = keys_.data();
  std::uint32_t* order = order_.data();
  std::uint32_t* start = cell_start_.data();
  const Axes g = axes_of(spec_);

  auto key_at = [&](std::size_t i) {
    return in_grid && !in_grid[i] ? outside : key_of(g, x[i], y[i], z[i]);
  };
  std::atomic<bool> sorted{true};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kBlock), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) key[i] = key_at(i);
    bool ok = r.begin() == 0 || key_at(r.begin() - 1) <= key[r.begin()];
    for (std::size_t i = r.begin() + 1; i < r.end(); ++i) ok &= key[i - 1] <= key[i];
    if (!ok) sorted.store(false, std::memory_order_relaxed);
  });

  if (sorted.load()) {
    // Identity order; bucket c starts at the first i with key[i] >= c.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n + 1, kBlock), [&](const auto& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        if (i < n) order[i] = std::uint32_t(i);
        const std::size_t lo = i == 0 ? 0 : std::size_t(key[i - 1]) + 1;
        const std::size_t hi = i == n ? cells + 1 : key[i];
        for (std::size_t c = lo; c <= hi; ++c) start[c] = std::uint32_t(i);
      }
    });
  } else {
    std::fill(start, start + cells + 2, 0u);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kBlock), [&](const auto& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i)
        std::atomic_ref<std::uint32_t>(start[key[i]]).fetch_add(1, std::memory_order_relaxed);
    });
    detail::exclusive_scan_in_place(start, cells + 2);
    // Scatter; each bucket's cursor runs from its start to its end = the next bucket's start.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kBlock), [&](const auto& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i)
        order[std::atomic_ref<std::uint32_t>(start[key[i]]).fetch_add(1, std::memory_order_relaxed)] =
            std::uint32_t(i);
    });
    std::copy_backward(start, start + cells + 1, start + cells + 2);  // ends back to starts
    start[0] = 0;
    // Stability: input order within each bucket (usually already so: one thread filled it).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells + 1, kBlock), [&](const auto& r) {
      for (std::size_t c = r.begin(); c < r.end(); ++c)
        if (!std::is_sorted(order + start[c], order + start[c + 1]))
          std::sort(order + start[c], order + start[c + 1]);
    });
  }
  num_in_grid_ = start[cells];
}

std::size_t CellGrid::bytes() const {
  return (keys_.capacity() + order_.capacity() + cell_start_.capacity()) * sizeof(std::uint32_t);
}

}  // namespace seiche::neighbor
