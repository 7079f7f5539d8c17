// What a run reports per frame: the state's health and the error of every active constraint
// family (only the families the scene has are filled in).
#pragma once

#include <cstddef>
#include <optional>
#include <span>

namespace seiche {

struct FluidError {
  double mean = 0.0;  ///< mean over fluid particles of max(rho / rho0 - 1, 0)
  double max = 0.0;   ///< max over fluid particles of the same
};

struct DistanceConstraintError {
  double mean = 0.0;  ///< mean |C| / rest_length (|C| in m for zero rest length)
  double max = 0.0;
};

struct ClothError {
  double strain_mean = 0.0;   ///< mean |l - l0| / l0 over the stretch constraints (edges)
  double strain_max = 0.0;
  double bending_mean = 0.0;  ///< mean |theta - theta0| over the hinges (rad)
  double bending_max = 0.0;
};

struct FrameMetrics {
  int frame = 0;                  ///< 1-based
  double time = 0.0;              ///< simulated time at the end of the frame (s)
  std::size_t particles = 0;
  double kinetic_energy = 0.0;    ///< J, sum of m v^2 / 2 over free particles
  /// J, gravitational energy sum of -m g . (x - domain.min) over free particles (zero on the
  /// domain's lowest corner), so that kinetic + potential is the mechanical energy.
  double potential_energy = 0.0;
  double max_speed = 0.0;         ///< m/s
  std::size_t non_finite = 0;     ///< count of NaN / inf values in positions and velocities
  std::size_t outside_domain = 0; ///< particles whose position is outside the domain box
  /// Constraint iterations per substep in this frame: their mean and the most in one substep
  /// (more than solver.iterations only with a density tolerance).
  double iterations_mean = 0.0;
  int iterations_max = 0;
  std::optional<FluidError> fluid;
  std::optional<DistanceConstraintError> distance;
  std::optional<ClothError> cloth;
};

/// A constraint family's error over a run: the mean over frames of the frame's mean, and the
/// largest frame max.
struct RunError {
  double mean = 0.0;
  double max = 0.0;
};

/// Every active family's error over a run (a family absent from the scene stays empty).
struct RunErrors {
  std::optional<RunError> density;   ///< fluid density error
  std::optional<RunError> distance;  ///< raw distance constraints, |C| / rest_length
  std::optional<RunError> strain;    ///< cloth strain
  std::optional<RunError> bending;   ///< cloth bending error (rad)
};
RunErrors summarize_errors(std::span<const FrameMetrics> frames);

}  // namespace seiche
