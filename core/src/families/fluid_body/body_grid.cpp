// The bodies' grid for the fluid-body passes (body_grid.hpp).
#include "body_grid.hpp"

#include <algorithm>
#include <cmath>

namespace seiche::fluid_body {

using rigid::Vec3d;

void BodyGrid::build(std::span<const Vec3d> centres, std::span<const double> reaches) {
  start_.assign(1, 0);
  bodies_.clear();
  dims_[0] = dims_[1] = dims_[2] = 0;
  if (centres.empty()) return;
  Vec3d lo = centres[0], hi = centres[0];
  double largest = 0.0;
  for (std::size_t k = 0; k < centres.size(); ++k) {
    const Vec3d r{reaches[k], reaches[k], reaches[k]};
    const Vec3d a = centres[k] - r, b = centres[k] + r;
    lo = {std::min(lo.x, a.x), std::min(lo.y, a.y), std::min(lo.z, a.z)};
    hi = {std::max(hi.x, b.x), std::max(hi.y, b.y), std::max(hi.z, b.z)};
    largest = std::max(largest, reaches[k]);
  }
  const Vec3d extent = hi - lo;
  // The cell: half the largest reach, grown until the cells number at most kCellsPerBody per body.
  const double max_cells = double(kCellsPerBody * centres.size());
  double cell = std::max(0.5 * largest, 1e-9);
  const auto count = [&](double a) {
    return std::ceil(extent.x / a + 1e-9) * std::ceil(extent.y / a + 1e-9) * std::ceil(extent.z / a + 1e-9);
  };
  while (count(cell) > max_cells) cell *= 1.25;
  lo_ = lo;
  inverse_cell_ = 1.0 / cell;  // cell >= 1e-9
  dims_[0] = std::max(1, int(std::ceil(extent.x * inverse_cell_ + 1e-9)));
  dims_[1] = std::max(1, int(std::ceil(extent.y * inverse_cell_ + 1e-9)));
  dims_[2] = std::max(1, int(std::ceil(extent.z * inverse_cell_ + 1e-9)));
  const std::size_t cells = std::size_t(dims_[0]) * std::size_t(dims_[1]) * std::size_t(dims_[2]);
  // Two sweeps over the bodies in ascending k: count per cell, then fill (each list ascending).
  const auto range = [&](std::size_t k, int axis, int& first, int& last) {
    const double c = axis == 0 ? centres[k].x : axis == 1 ? centres[k].y : centres[k].z;
    const double l = axis == 0 ? lo_.x : axis == 1 ? lo_.y : lo_.z;
    first = std::clamp(int(std::floor((c - reaches[k] - l) * inverse_cell_)), 0, dims_[axis] - 1);
    last = std::clamp(int(std::floor((c + reaches[k] - l) * inverse_cell_)), 0, dims_[axis] - 1);
  };
  const auto for_cells = [&](std::size_t k, auto&& visit) {
    int x0, x1, y0, y1, z0, z1;
    range(k, 0, x0, x1), range(k, 1, y0, y1), range(k, 2, z0, z1);
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) visit((std::size_t(z) * dims_[1] + y) * dims_[0] + x);
  };
  start_.assign(cells + 1, 0);
  for (std::size_t k = 0; k < centres.size(); ++k) for_cells(k, [&](std::size_t c) { ++start_[c + 1]; });
  for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
  bodies_.resize(start_[cells]);
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (std::size_t k = 0; k < centres.size(); ++k)
    for_cells(k, [&](std::size_t c) { bodies_[fill[c]++] = std::uint32_t(k); });
}

std::span<const std::uint32_t> BodyGrid::candidates(Vec3d p) const {
  if (bodies_.empty()) return {};
  const double f[3] = {(p.x - lo_.x) * inverse_cell_, (p.y - lo_.y) * inverse_cell_, (p.z - lo_.z) * inverse_cell_};
  int cell[3];
  for (int a = 0; a < 3; ++a) {
    if (!(f[a] >= 0.0) || f[a] >= double(dims_[a])) return {};  // outside, or not finite
    cell[a] = int(f[a]);
  }
  const std::size_t c = (std::size_t(cell[2]) * dims_[1] + cell[1]) * dims_[0] + cell[0];
  return {bodies_.data() + start_[c], bodies_.data() + start_[c + 1]};
}

}  // namespace seiche::fluid_body
