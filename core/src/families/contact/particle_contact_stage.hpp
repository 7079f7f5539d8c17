// The particle contact stage: finds, once per substep on the predicted positions, the pairs of
// particles that may touch during the substep, and solves their contacts every iteration
// (kernels/particle_contacts.hpp). Pairs:
//   cloth-cloth, same cloth    only if the cloth has self_collision, and only for vertices that
//                              share no triangle; contact distance = the cloth's thickness
//   cloth-cloth, two cloths    always; contact distance = the mean of their thicknesses
//   cloth-fluid                when the scene has fluid; contact distance = half the cloth's
//                              thickness + the fluid particle radius
//   shape-shape, two shapes    always; contact distance = the sum of their collision radii (half
//                              of each shape's spacing); a shape's own particles never touch
//   shape-cloth                always; contact distance = half the shape's spacing + half the
//                              cloth's thickness
//   shape-fluid                when the scene has fluid; contact distance = half the shape's
//                              spacing + the fluid particle radius; solved apart, keeping each
//                              pair's momentum (kernels::solve_sided_contacts: the fluid particle's
//                              corrections averaged, the shape particle gets the sum of their
//                              reactions, which shape matching spreads over its cluster), with
//                              the same friction as the other pairs. The fluid's density sees
//                              shapes as its boundary too (fluid_body/shape_boundary.hpp); these
//                              contacts keep it out of them.
// Cloth particles, and shape particles within reach of another shape's, a cloth's or the fluid's
// box, go into a grid of their own (the store is not reordered for it);
// fluid partners are found in the fluid's neighbor grid. A pair is a candidate when closer than
// kCandidateMargin times its contact distance, so contacts that close during the iterations
// are not missed. Lists are in a fixed order: results do not depend on the thread count.
// Friction: the largest of the cloths' `friction` for every pair, fluid-shape pairs included (a
// shape and a fluid have no coefficient of their own: in a scene without cloth two shapes, or a
// shape and the fluid, slide on each other without friction).
#pragma once

#include <cmath>
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

  /// Whether a scene needs this stage: a cloth with self_collision, two cloths, cloth and fluid,
  /// or shapes that touch (shapes_touch).
  static bool needed(const SceneDef& scene);
  /// Whether shape particles take part: two shapes or more, or a shape and a cloth or fluid.
  static bool shapes_touch(const SceneDef& scene);

  /// `cloth`: the scene's cloths, or null without cloth; fluid_radius: collision radius of
  /// fluid particles (0 without fluid).
  ParticleContactStage(const ClothSolver* cloth, const SceneDef& scene, float fluid_radius);

  /// Candidate pairs on the predicted positions. `fluid`: the fluid's neighbor stage, built on
  /// the same positions (fluid particles are store indices [0, fluid->count())), or null.
  void find_candidates(const ParticleStore& store, const Neighborhood* fluid);
  void solve(const kernels::ParticleView& p);

 private:
  void find_shape_partner_boxes(const ParticleStore& store);
  bool near_a_partner(const ParticleStore& store, std::size_t i) const;
  struct FluidShapePair {
    std::uint32_t shape, fluid;
    float distance;
  };
  void build_fluid_shape_contacts(std::vector<FluidShapePair>& shape_ordered_pairs);
  template <class Visit>
  void visit_candidates(const ParticleStore& store, const Neighborhood* fluid, std::uint32_t i, Visit&& visit) const;

  const ClothSolver* cloth_;  // null without cloth
  float fluid_radius_ = 0.0f;
  bool with_shapes_ = false;  // shape particles are in the grid (shapes_touch)
  std::size_t shape_count_ = 0;  // with shapes: the scene's shapes
  // With shapes, per substep: a box per shape and one for all the cloth, around their particles
  // grown by the largest candidate distance; per shape, the other boxes that meet its own; with
  // fluid, last, the fluid's box grown by fluid_reach_ (every shape's partner). Only a shape
  // particle inside one of those goes into the grid (near_a_partner).
  struct Box {
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  };
  std::vector<Box> boxes_;
  std::vector<std::vector<std::uint32_t>> partner_boxes_;
  float max_distance_ = 0.0f;  // largest contact distance between grid particles
  float fluid_reach_ = 0.0f;   // with shapes and fluid: the largest fluid-shape candidate distance
  float friction_ = 0.0f;
  float domain_min_[3] = {0, 0, 0}, domain_max_[3] = {0, 0, 0};
  neighbor::CellGrid grid_;
  std::vector<std::uint8_t> in_grid_;
  // Scratch of the candidate search, rebuilt from the store's px, py, pz every substep and never
  // written back (the store owns the positions): grid particles in grid order: x, y, z, (unused).
  std::vector<kernels::Float4> sorted_;
  std::vector<std::uint32_t> grid_particles_;  // store indices of the cloth (and shape) particles
  std::vector<std::uint32_t> count_, slot_partner_;  // per grid particle: kMaxCandidates slots
  std::vector<float> slot_distance_;
  kernels::ParticleContacts contacts_;
  kernels::SidedContacts fluid_shape_;  // fluid particles (first) against shape particles
  std::vector<float> scratch_;
};

}  // namespace seiche
