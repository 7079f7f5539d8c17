#include "seiche/particle_store.hpp"

#include <cstring>
#include <type_traits>

#include <tbb/parallel_for.h>

namespace seiche {

template <class F>
void ParticleStore::for_each_state_column(F&& f) {
  for (FloatColumn* c : {&x, &y, &z, &px, &py, &pz, &vx, &vy, &vz, &w}) f(*c);
  f(phase);
  f(id);
}

void ParticleStore::resize(std::size_t n) {
  size_ = n;
  for_each_state_column([n](auto& c) { c.resize(n); });
  if (fluid_columns_) enable_fluid_columns();
  if (vorticity_columns_) enable_vorticity_columns();
}

void ParticleStore::enable_fluid_columns() {
  fluid_columns_ = true;
  density.resize(size_);
  lambda.resize(size_);
}

void ParticleStore::enable_vorticity_columns() {
  vorticity_columns_ = true;
  omega_x.resize(size_);
  omega_y.resize(size_);
  omega_z.resize(size_);
}

void ParticleStore::reorder(std::span<const std::uint32_t> order) {
  const std::size_t n = size_;
  scratch_float_.resize(n);
  scratch_int_.resize(n);
  // Gather each column into a scratch buffer, then copy back: one column's worth of extra memory.
  for_each_state_column([&](auto& column) {
    using T = std::remove_reference_t<decltype(column[0])>;
    T* src = column.data();
    T* tmp;
    if constexpr (std::is_same_v<T, float>) {
      tmp = scratch_float_.data();
    } else {  // int32 and uint32 may alias each other
      tmp = reinterpret_cast<T*>(scratch_int_.data());
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t k = r.begin(); k != r.end(); ++k) tmp[k] = src[order[k]];
                      });
    std::memcpy(src, tmp, n * sizeof(T));
  });
}

std::vector<std::uint32_t> ParticleStore::index_of_id() const {
  std::vector<std::uint32_t> index(size_);
  for (std::size_t i = 0; i < size_; ++i) index[std::size_t(id[i])] = std::uint32_t(i);
  return index;
}

std::size_t ParticleStore::bytes() const {
  std::size_t b = 0;
  for (const FloatColumn* c : {&x, &y, &z, &px, &py, &pz, &vx, &vy, &vz, &w, &density, &lambda,
                               &omega_x, &omega_y, &omega_z})
    b += c->bytes();
  return b + phase.bytes() + id.bytes();
}

std::vector<std::uint32_t> inverse_permutation(std::span<const std::uint32_t> order) {
  std::vector<std::uint32_t> inv(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) inv[order[k]] = std::uint32_t(k);
  return inv;
}

}  // namespace seiche
