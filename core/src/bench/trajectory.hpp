// A run's particle positions frame by frame, in id order, and the difference of another run to
// it: what `seiche bench` measures a setting's error with (bench.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "seiche/particle_store.hpp"

namespace seiche {

class Trajectory {
 public:
  explicit Trajectory(std::size_t particles) : particles_(particles) {}

  /// Appends the store's positions as the next frame.
  void add_frame(const ParticleStore& store);
  /// Appends a frame given in store order with the store index -> id map (double positions).
  void add_frame(std::span<const double> xyz, std::span<const std::int32_t> id_of_index);

  std::size_t frames() const { return particles_ ? xyz_.size() / (3 * particles_) : 0; }
  std::size_t particles() const { return particles_; }
  /// Frame f (0-based): x, y, z of particle id k at [3k, 3k + 3).
  std::span<const float> frame(std::size_t f) const {
    return {xyz_.data() + f * 3 * particles_, 3 * particles_};
  }

 private:
  std::size_t particles_;
  std::vector<float> xyz_;
};

/// Position differences against a reference trajectory, accumulated frame by frame (m).
class TrajectoryDifference {
 public:
  explicit TrajectoryDifference(const Trajectory& reference) : reference_(reference) {}

  /// Adds frame f (0-based) of the compared run, given by its store.
  void add_frame(std::size_t f, const ParticleStore& store);
  /// Adds frame f of a whole trajectory.
  void add_frame(std::size_t f, const Trajectory& run);

  double rms() const;  ///< root mean square over every particle of every added frame
  double max() const { return max_; }

 private:
  void add(double squared_distance);

  const Trajectory& reference_;
  double sum_squares_ = 0.0, max_ = 0.0;
  std::size_t count_ = 0;
};

}  // namespace seiche
