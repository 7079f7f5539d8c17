#include "neighborhood.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "seiche/phase.hpp"

namespace seiche {

void Neighborhood::build_grid(const float* x, const float* y, const float* z, const std::uint32_t* phase,
                              std::size_t n) {
  in_grid.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i)
      in_grid[i] = phase_material(phase[i]) == Material::Fluid ? 1 : 0;
  });
  grid.build(spec, x, y, z, in_grid.data(), n);
}

}  // namespace seiche
