// The particle contact stage: finds, once per substep on the predicted positions, the pairs of
// particles that may touch during the substep, and solves their contacts every iteration
// (kernels/particle_contacts.hpp). Pairs:
//   cloth-cloth, same cloth    only if the cloth has self_collision, and only for vertices that
//                              share no triangle; contact distance = the cloth's thickness
//   cloth-cloth, two cloths    always; contact distance = the mean of their thicknesses
//   cloth-fluid                when the scene has fluid; contact distance = half the cloth's
//                              thickness + the fluid particle radius
// Cloth particles go into a grid of their own (the store is not reordered for it); fluid
// partners are found in the fluid's neighbor grid. A pair is a candidate when closer than
// kCandidateMargin times its contact distance, so contacts that close during the iterations
// are not missed. Lists are in a fixed order: results do not depend on the thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "families/cloth/cloth_solver.hpp"
#include "families/fluid/neighborhood.hpp"
#include "seiche/kernels/particle_contacts.hpp"
#include "seiche/neighbor/cell_grid.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class ParticleContactStage {
 public:
  static constexpr float kCandidateMargin = 1.5f;
  /// At most this many candidates per cloth particle (the first found, in a fixed order); only
  /// a pile of crumpled cloth reaches it.
  static constexpr std::uint32_t kMaxCandidates = 48;

  /// Whether a scene needs this stage: a cloth with self_collision, two cloths, or cloth and fluid.
  static bool needed(const SceneDef& scene);

  /// fluid_radius: collision radius of fluid particles (0 without fluid).
  ParticleContactStage(const ClothSolver& cloth, const DomainDef& domain, float fluid_radius);

  /// Candidate pairs on the predicted positions. `fluid`: the fluid's neighbor stage, built on
  /// the same positions (fluid particles are store indices [0, fluid->count())), or null.
  void find_candidates(const ParticleStore& store, const Neighborhood* fluid);
  void solve(const kernels::ParticleView& p);

 private:
  template <class Visit>
  void visit_candidates(const ParticleStore& store, const Neighborhood* fluid, std::uint32_t i, Visit&& visit) const;

  const ClothSolver& cloth_;
  float fluid_radius_ = 0.0f;
  float max_cloth_distance_ = 0.0f;  // largest cloth-cloth contact distance
  float friction_ = 0.0f;
  float domain_min_[3] = {0, 0, 0}, domain_max_[3] = {0, 0, 0};
  neighbor::CellGrid grid_;
  std::vector<std::uint8_t> in_grid_;
  // Scratch of the candidate search, rebuilt from the store's px, py, pz every substep and never
  // written back (the store owns the positions): cloth particles in grid order: x, y, z, (unused).
  std::vector<kernels::Float4> sorted_;
  std::vector<std::uint32_t> cloth_particles_;  // store indices of the cloth particles
  std::vector<std::uint32_t> count_, slot_partner_;  // per cloth particle: kMaxCandidates slots
  std::vector<float> slot_distance_;
  kernels::ParticleContacts contacts_;
  std::vector<float> scratch_;
};

}  // namespace seiche
