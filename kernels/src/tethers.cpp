// Long-range attachments (tethers.hpp; Kim, Chentanez and Müller 2012):
//   C = |p_i - p_a| - L <= 0;  when violated, p_i = p_a + L (p_i - p_a) / |p_i - p_a|
// (the anchor is pinned, so the whole correction goes to p_i). Groups (one tethered particle
// each) run in parallel; the tethers of a group one after another, in their stored order.
#include "seiche/kernels/tethers.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

namespace seiche::kernels {

void Tethers::remap(std::span<const std::uint32_t> new_index) {
  for (std::uint32_t& k : particle) k = new_index[k];
  for (std::uint32_t& k : anchor) k = new_index[k];
}

void solve_tethers(const ParticleView& p, const Tethers& t) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, t.groups(), 1024), [&](const auto& r) {
    for (std::size_t g = r.begin(); g != r.end(); ++g) {
      const std::uint32_t i = t.particle[g];
      if (p.w[i] <= 0.0f) continue;  // a pinned particle is not pulled
      float x = p.px[i], y = p.py[i], z = p.pz[i];
      for (std::uint32_t k = t.start[g]; k < t.start[g + 1]; ++k) {
        const std::uint32_t a = t.anchor[k];
        const float dx = x - p.px[a], dy = y - p.py[a], dz = z - p.pz[a];
        const float len2 = dx * dx + dy * dy + dz * dz;
        const float L = t.max_length[k];
        if (!(len2 > L * L)) continue;  // within reach (or NaN: left for the finite check)
        const float s = L / std::sqrt(len2);
        x = p.px[a] + s * dx;
        y = p.py[a] + s * dy;
        z = p.pz[a] + s * dz;
      }
      p.px[i] = x, p.py[i] = y, p.pz[i] = z;
    }
  });
}

}  // namespace seiche::kernels
