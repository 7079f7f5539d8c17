// Shape-matched particles as the fluid's boundary particles (Akinci et al. 2012, as the rigid
// bodies' sites in body_boundary.hpp, but each a particle of the store that moves on its own).
//
// Volume of shape particle b, over the particles k of its own shape at rest (b included), with
// the fluid's poly6 W of support h, once when the scene is built:
//   psi_b = 1 / sum_k W(|q_b - q_k|)
// (the rest lattice's positions, so a deformed or plastic shape keeps its volumes).
// Pairs (fluid particle i, shape particle b) closer than h, found once per substep on the
// predicted positions in the fluid's neighbor grid (as the fluid's own neighbor lists: kept over
// the iterations, a pair that separates beyond h weighs 0), shape-major (shape particles in store
// order, each one's fluid partners in the grid's cell order), and transposed fluid-major (a
// counting sort in pair order). Per iteration:
//   gather (before the fluid's density pass), per fluid particle i:
//     rho_s,i = sum_b rho0 psi_b W(|p_i - x_b|),   g_e = psi_b grad W(p_i - x_b) per pair e,
//     g_s,i = sum_e g_e (added to the bodies' boundary, kernels/pbf_density.hpp)
//   solve (after it), with the fluid's lambda_i of this iteration (lambda_i < 0: compressed):
//     dp_i = lambda_i g_s,i
//     dx_b = -w_b m sum_{e of b} lambda_i g_e   (the pair's momentum kept: m dp + m_b dx = 0)
//   and shape matching then spreads dx_b over b's clusters.
// Every sum runs over a list in a fixed order and each particle writes only itself: the same bits
// on any thread count. Nothing is carried across substeps.
#pragma once

#include <cstdint>
#include <vector>

#include "families/fluid/neighborhood.hpp"
#include "seiche/kernels/sph_kernels.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche::fluid_body {

class ShapeBoundary {
 public:
  /// `first_id`: the id of the scene's first shape particle (shape particles have consecutive
  /// ids in scene order); h: the fluid's kernel radius (m).
  ShapeBoundary(const SceneDef& scene, std::int32_t first_id, double h);

  /// The pairs on the predicted positions of this substep (after the fluid's neighbor stage).
  void find_pairs(const ParticleStore& store, const Neighborhood& fluid);
  /// Adds fluid particle i's rho_s,i and g_s,i (world frame) and keeps each pair's g_e.
  void gather(const ParticleStore& store, std::size_t i, double rest_density, const kernels::SphKernel& kernel,
              double& density, double gradient[3]);
  /// The correction of the fluid particles (their lambda in store.lambda) and the shape
  /// particles' reaction; `mass`: the fluid particle's mass.
  void solve(ParticleStore& store, std::size_t fluid_count, double mass) const;

  /// Calls visit(shape particle b, psi_b) for fluid particle i's pairs of this substep, in pair
  /// order.
  template <class Visit>
  void for_each_pair_of(std::size_t i, Visit&& visit) const {
    if (i + 1 >= fluid_start_.size()) return;
    for (std::uint32_t k = fluid_start_[i]; k < fluid_start_[i + 1]; ++k) {
      const std::uint32_t e = fluid_pair_[k];
      visit(pair_shape_[e], pair_psi_[e]);
    }
  }

  /// The shape particles with pairs this substep, shape-major: g in [0, shape_count()) is store
  /// index shape_particle(g); for_each_pair_of_shape(g, visit) calls visit(fluid particle j, psi_b)
  /// for its pairs, in pair order.
  std::size_t shape_count() const { return shape_particle_.size(); }
  std::uint32_t shape_particle(std::size_t g) const { return shape_particle_[g]; }
  template <class Visit>
  void for_each_pair_of_shape(std::size_t g, Visit&& visit) const {
    for (std::uint32_t e = shape_start_[g]; e < shape_start_[g + 1]; ++e) visit(pair_fluid_[e], pair_psi_[e]);
  }

  bool empty() const { return shape_particle_.empty(); }
  /// psi_b of shape particle with id `id` (m^3).
  double volume(std::int32_t id) const { return psi_[std::size_t(id - first_id_)]; }

 private:
  std::int32_t first_id_ = 0;
  std::vector<double> psi_;                    // per shape particle, by id - first_id_
  // Shape-major pairs: shape_particle_[g] (a store index) has pairs [shape_start_[g], shape_start_[g + 1]).
  std::vector<std::uint32_t> shape_particle_, shape_start_, pair_fluid_;
  std::vector<double> pair_psi_;               // per pair: psi of its shape particle
  std::vector<std::uint32_t> pair_shape_;      // per pair: its shape particle (store index)
  std::vector<double> pair_gradient_;          // per pair: g_e (3 doubles), written by gather
  // Fluid-major: fluid particle i's pairs are fluid_pair_[fluid_start_[i] .. fluid_start_[i + 1]).
  std::vector<std::uint32_t> fluid_start_, fluid_pair_;
};

}  // namespace seiche::fluid_body
