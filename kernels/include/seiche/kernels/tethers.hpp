// Long-range attachments (Kim, Chentanez and Müller 2012): every cloth vertex may be no farther
// from a pinned vertex than its rest (geodesic) distance to it. An inequality constraint,
//   C = |p_i - p_a| - L <= 0,   p_i += (L - |p_i - p_a|) (p_i - p_a) / |p_i - p_a|  when C > 0,
// stiff (no compliance). The anchor a is pinned (w = 0), so only p_i moves; tethers of one
// particle are applied one after another, particles in parallel (no two groups share p_i).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

struct Tethers {
  std::vector<std::uint32_t> particle;  ///< one per group: the tethered particle
  std::vector<std::uint32_t> start;     ///< group g owns entries [start[g], start[g + 1])
  std::vector<std::uint32_t> anchor;    ///< per entry: a pinned particle
  std::vector<float> max_length;        ///< per entry: L (m)

  std::size_t groups() const { return particle.size(); }
  void remap(std::span<const std::uint32_t> new_index);
};

void solve_tethers(const ParticleView& p, const Tethers& t);

}  // namespace seiche::kernels
