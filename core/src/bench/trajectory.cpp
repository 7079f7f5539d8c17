#include "trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace seiche {

void Trajectory::add_frame(const ParticleStore& store) {
  if (store.size() != particles_) throw std::invalid_argument("Trajectory: another particle count");
  const std::size_t first = xyz_.size();
  xyz_.resize(first + 3 * particles_);
  float* out = xyz_.data() + first;
  for (std::size_t i = 0; i < particles_; ++i) {
    const std::size_t k = 3 * std::size_t(store.id[i]);
    out[k] = store.x[i], out[k + 1] = store.y[i], out[k + 2] = store.z[i];
  }
}

void Trajectory::add_frame(std::span<const double> xyz, std::span<const std::int32_t> id_of_index) {
  if (xyz.size() != 3 * particles_ || id_of_index.size() != particles_)
    throw std::invalid_argument("Trajectory: another particle count");
  const std::size_t first = xyz_.size();
  xyz_.resize(first + 3 * particles_);
  float* out = xyz_.data() + first;
  for (std::size_t i = 0; i < particles_; ++i)
    for (std::size_t a = 0; a < 3; ++a) out[3 * std::size_t(id_of_index[i]) + a] = float(xyz[3 * i + a]);
}

void TrajectoryDifference::add(double squared_distance) {
  sum_squares_ += squared_distance;
  // A non-finite difference makes the error infinite (std::max would drop a NaN).
  max_ = std::isfinite(squared_distance) ? std::max(max_, std::sqrt(squared_distance))
                                         : std::numeric_limits<double>::infinity();
  ++count_;
}

void TrajectoryDifference::add_frame(std::size_t f, const ParticleStore& store) {
  const std::span<const float> ref = reference_.frame(f);
  for (std::size_t i = 0; i < store.size(); ++i) {
    const float* r = ref.data() + 3 * std::size_t(store.id[i]);
    const double dx = double(store.x[i]) - r[0], dy = double(store.y[i]) - r[1], dz = double(store.z[i]) - r[2];
    add(dx * dx + dy * dy + dz * dz);
  }
}

void TrajectoryDifference::add_frame(std::size_t f, const Trajectory& run) {
  const std::span<const float> ref = reference_.frame(f), x = run.frame(f);
  for (std::size_t k = 0; k < x.size(); k += 3) {
    const double dx = double(x[k]) - ref[k], dy = double(x[k + 1]) - ref[k + 1], dz = double(x[k + 2]) - ref[k + 2];
    add(dx * dx + dy * dy + dz * dz);
  }
}

double TrajectoryDifference::rms() const {
  if (!std::isfinite(max_)) return std::numeric_limits<double>::infinity();
  return count_ ? std::sqrt(sum_squares_ / double(count_)) : 0.0;
}

}  // namespace seiche
