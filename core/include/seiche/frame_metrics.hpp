// What a run reports per frame: the state's health and the error of every active constraint
// family (only the families the scene has are filled in).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace seiche {

/// How an error row reads: a ratio (the summary and the bench show it in percent) or an angle in
/// radians (shown in degrees).
enum class ErrorUnit { Ratio, Radians };

/// One error of a constraint family, over a frame or over a run. Each family adds its rows in
/// Family::measure (core/src/loop/family.hpp); the run report, the summary, the bench and the
/// stability suite show every row they are given, so a new family needs none of them changed.
struct ErrorRow {
  std::string key;    ///< the run report's key: "fluid_density_error", "cloth_strain", ...
  std::string label;  ///< the summary's and the bench's name: "fluid density", "cloth strain", ...
  ErrorUnit unit = ErrorUnit::Ratio;
  double mean = 0.0;
  double max = 0.0;
};

/// The row of `key` among `rows`, or null.
const ErrorRow* find_error(std::span<const ErrorRow> rows, std::string_view key);

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
  /// Every active family's errors, in the order of the families (empty when not measured).
  std::vector<ErrorRow> errors;
  const ErrorRow* error(std::string_view key) const { return find_error(errors, key); }
};

/// Every active family's errors over a run: per row, the mean over frames of the frame's mean and
/// the largest frame max, in the order the rows first appear.
using RunErrors = std::vector<ErrorRow>;
RunErrors summarize_errors(std::span<const FrameMetrics> frames);

}  // namespace seiche
