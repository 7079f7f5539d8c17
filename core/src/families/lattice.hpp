// The particles of a box filled on a cubic lattice (fluid blocks, shapes): sites at
// (i + 0.5) spacing from box.min along each axis, floor(extent / spacing + 1e-4) of them per axis
// (the 1e-4 keeps a box of exactly k spacings at k sites despite rounding), x fastest, then y,
// then z.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "seiche/scene.hpp"

namespace seiche {

inline std::array<std::size_t, 3> lattice_counts(const BoxDef& box, float spacing) {
  std::array<std::size_t, 3> n{};
  for (int a = 0; a < 3; ++a) {
    const double extent = double(box.max[a]) - box.min[a];
    n[a] = std::size_t(std::max(0.0, std::floor(extent / spacing + 1e-4)));
  }
  return n;
}

inline std::size_t lattice_size(const BoxDef& box, float spacing) {
  const auto n = lattice_counts(box, spacing);
  return n[0] * n[1] * n[2];
}

/// site(x, y, z) for every site, in the lattice order.
template <class Site>
void for_each_lattice_site(const BoxDef& box, float spacing, Site&& site) {
  const auto n = lattice_counts(box, spacing);
  for (std::size_t iz = 0; iz < n[2]; ++iz)
    for (std::size_t iy = 0; iy < n[1]; ++iy)
      for (std::size_t ix = 0; ix < n[0]; ++ix)
        site(box.min[0] + (float(ix) + 0.5f) * spacing, box.min[1] + (float(iy) + 0.5f) * spacing,
             box.min[2] + (float(iz) + 0.5f) * spacing);
}

}  // namespace seiche
