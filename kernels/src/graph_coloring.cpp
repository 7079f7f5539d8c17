// Greedy graph coloring of constraints (graph_coloring.hpp): constraints are visited in input
// order and each takes the lowest color that none of its particles uses yet; then a stable
// counting sort lists the constraints color by color. Serial and order-dependent only on the
// input, so the coloring (and every solve that walks it) is the same with any thread count.
#include "seiche/kernels/graph_coloring.hpp"

#include <algorithm>
#include <bit>
#include <cassert>

namespace seiche::kernels {

Coloring color_constraints(std::span<const std::uint32_t> particles, std::size_t arity,
                           std::size_t particle_count) {
  Coloring out;
  const std::size_t m = arity == 0 ? 0 : particles.size() / arity;
  assert(m * arity == particles.size());

  // Colors in use per particle: `words` 64-bit masks per particle in one flat array
  // (used[p * words + w], bit b of word w = color 64 w + b). Cloth needs fewer than 64 colors,
  // so this is one word per particle; it grows (and is re-laid out) only if a constraint
  // needs a color past the last word.
  std::size_t words = 1;
  std::vector<std::uint64_t> used(particle_count * words, 0);
  std::vector<std::uint32_t> color(m);
  std::uint32_t num_colors = 0;

  for (std::size_t c = 0; c < m; ++c) {
    const std::uint32_t* v = particles.data() + c * arity;
    std::uint32_t k = 0;
    for (std::size_t word = 0;; ++word) {
      if (word == words) {  // all colors so far are taken: one more word per particle
        std::vector<std::uint64_t> grown(particle_count * (words + 1), 0);
        for (std::size_t p = 0; p < particle_count; ++p)
          std::copy_n(used.begin() + p * words, words, grown.begin() + p * (words + 1));
        used.swap(grown);
        ++words;
      }
      std::uint64_t taken = 0;
      for (std::size_t s = 0; s < arity; ++s) {
        assert(v[s] < particle_count);
        taken |= used[v[s] * words + word];
      }
      if (taken != ~std::uint64_t(0)) {
        k = std::uint32_t(word * 64 + std::countr_one(taken));  // lowest free bit
        break;
      }
    }
    const std::size_t word = k / 64;
    const std::uint64_t bit = std::uint64_t(1) << (k % 64);
    for (std::size_t s = 0; s < arity; ++s) used[v[s] * words + word] |= bit;
    color[c] = k;
    num_colors = std::max(num_colors, k + 1);
  }

  // Stable counting sort by color.
  out.color_start.assign(std::size_t(num_colors) + 1, 0);
  for (std::size_t c = 0; c < m; ++c) ++out.color_start[color[c] + 1];
  for (std::uint32_t k = 0; k < num_colors; ++k) out.color_start[k + 1] += out.color_start[k];
  std::vector<std::uint32_t> cursor(out.color_start.begin(), out.color_start.end() - 1);
  out.order.resize(m);
  for (std::size_t c = 0; c < m; ++c) out.order[cursor[color[c]]++] = std::uint32_t(c);
  return out;
}

}  // namespace seiche::kernels
