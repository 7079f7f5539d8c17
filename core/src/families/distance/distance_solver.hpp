// The raw distance constraints of a scene ("distance_constraints"), built once and solved with
// XPBD every iteration in two parts: first spanning forests of them (`solver.distance_forests`;
// by default one over the pieces without loops), solved exactly in linear time on the store's
// columns (kernels/distance_tree.hpp; grown from the pinned particles,
// kernels/shortest_path_forest.hpp), so that a load reaches the pins whatever the mass ratios
// along the way; then every constraint, color by color (Gauss-Seidel), on the iteration record
// (core/src/loop/iteration_record.hpp), which also solves the edges no forest holds. Their
// particle indices are remapped when the store is reordered.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "seiche/frame_metrics.hpp"
#include "seiche/kernels/distance_constraint.hpp"
#include "seiche/kernels/distance_tree.hpp"
#include "seiche/kernels/particle_view.hpp"

namespace seiche {

/// The raw distance constraints' error: the run report's "distance_error".
struct DistanceConstraintError {
  double mean = 0.0;  ///< mean |C| / rest_length (|C| in m for zero rest length)
  double max = 0.0;
};

class DistanceSolver {
 public:
  /// i, j are store indices at build time; rest_length < 0 means "the current distance". The
  /// particles of inverse mass 0 at build time are the pins the forests grow from. `forests`
  /// (solver.distance_forests): that many spanning forests over all constraints; absent: one
  /// over the pieces without loops (chains, trees), none over those with loops.
  DistanceSolver(std::span<const std::uint32_t> i, std::span<const std::uint32_t> j,
                 std::span<const float> rest_length, std::span<const float> compliance,
                 const kernels::ParticleView& particles, std::optional<int> forests);

  std::size_t size() const { return constraints_.size(); }
  std::size_t colors() const { return constraints_.color_start.size() - 1; }
  bool has_forests() const { return !forests_.empty(); }
  std::span<const kernels::DistanceForest> forests() const { return forests_; }
  /// Starts the substep's multipliers at 0; with forests, the last substep's go to their
  /// geometric stiffness first.
  void begin_substep();
  /// One iteration's first part: the forests, exactly, on the store's columns.
  void solve_forests(const kernels::ParticleView& p, float dt);
  /// One iteration's second part: every constraint, color by color, on the packed positions
  /// (their range covers packed_range()), accumulating lambda (reset by begin_substep).
  void solve(const kernels::PackedPositions& packed, float dt) {
    kernels::solve_distance_constraints(packed, constraints_, dt, kernels::Multipliers::Accumulate);
  }
  /// Every store index the constraints use.
  kernels::IndexRange packed_range() const { return kernels::index_range({constraints_.i, constraints_.j}); }
  void remap(std::span<const std::uint32_t> new_index);
  /// The multipliers of the last substep when there are forests (their geometric stiffness reads
  /// them in the next substep), else empty; restored from a checkpoint.
  std::span<const float> multipliers() const;
  void restore_multipliers(std::span<const float> saved);
  /// The constraints as built (store indices), for the implicit-Euler reference of the bench.
  const kernels::DistanceConstraints& constraints() const { return constraints_; }
  DistanceConstraintError measure(const kernels::ParticleView& p) const {
    const auto e = kernels::distance_constraint_error(p, constraints_);
    return {e.mean, e.max};
  }

 private:
  kernels::DistanceConstraints constraints_;
  std::vector<kernels::DistanceForest> forests_;
  std::vector<float> tension_;  // the multipliers of the previous substep, with forests
};

}  // namespace seiche
