#include "distance_solver.hpp"

#include <cmath>

namespace seiche {

DistanceSolver::DistanceSolver(std::span<const std::uint32_t> i, std::span<const std::uint32_t> j,
                               std::span<const float> rest_length,
                               std::span<const float> compliance,
                               const kernels::ParticleView& p) {
  std::vector<float> rest(rest_length.begin(), rest_length.end());
  for (std::size_t k = 0; k < rest.size(); ++k) {
    if (rest[k] >= 0.0f) continue;
    const float dx = p.x[i[k]] - p.x[j[k]], dy = p.y[i[k]] - p.y[j[k]], dz = p.z[i[k]] - p.z[j[k]];
    rest[k] = std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  kernels::color_distance_constraints(i, j, rest, compliance, p.n, constraints_);
}

}  // namespace seiche
