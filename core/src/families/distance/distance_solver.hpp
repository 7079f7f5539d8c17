// The raw distance constraints of a scene ("distance_constraints"): colored once at build time,
// solved with XPBD every iteration on the iteration record (core/src/loop/iteration_record.hpp),
// their particle indices remapped when the store is reordered.
#pragma once

#include <span>
#include <vector>

#include "seiche/frame_metrics.hpp"
#include "seiche/kernels/distance_constraint.hpp"
#include "seiche/kernels/particle_view.hpp"

namespace seiche {

/// The raw distance constraints' error: the run report's "distance_error".
struct DistanceConstraintError {
  double mean = 0.0;  ///< mean |C| / rest_length (|C| in m for zero rest length)
  double max = 0.0;
};

class DistanceSolver {
 public:
  /// i, j are store indices at build time; rest_length < 0 means "the current distance".
  DistanceSolver(std::span<const std::uint32_t> i, std::span<const std::uint32_t> j,
                 std::span<const float> rest_length, std::span<const float> compliance,
                 const kernels::ParticleView& particles);

  std::size_t size() const { return constraints_.size(); }
  std::size_t colors() const { return constraints_.color_start.size() - 1; }
  void begin_substep() { std::fill(constraints_.lambda.begin(), constraints_.lambda.end(), 0.0f); }
  /// One iteration on the packed positions (their range covers packed_range()), accumulating
  /// lambda (reset by begin_substep).
  void solve(const kernels::PackedPositions& packed, float dt) {
    kernels::solve_distance_constraints(packed, constraints_, dt, kernels::Multipliers::Accumulate);
  }
  /// Every store index the constraints use.
  kernels::IndexRange packed_range() const { return kernels::index_range({constraints_.i, constraints_.j}); }
  void remap(std::span<const std::uint32_t> new_index) {
    for (auto& k : constraints_.i) k = new_index[k];
    for (auto& k : constraints_.j) k = new_index[k];
  }
  /// The constraints as built (store indices), for the implicit-Euler reference of the bench.
  const kernels::DistanceConstraints& constraints() const { return constraints_; }
  DistanceConstraintError measure(const kernels::ParticleView& p) const {
    const auto e = kernels::distance_constraint_error(p, constraints_);
    return {e.mean, e.max};
  }

 private:
  kernels::DistanceConstraints constraints_;
};

}  // namespace seiche
