#include "seiche/particle_store.hpp"

#include <type_traits>

#include <tbb/parallel_for.h>

namespace seiche {

kernels::ParticleView particle_view(ParticleStore& store) {
  kernels::ParticleView v;
  v.n = store.size();
  v.x = store.x.data(), v.y = store.y.data(), v.z = store.z.data();
  v.px = store.px.data(), v.py = store.py.data(), v.pz = store.pz.data();
  v.vx = store.vx.data(), v.vy = store.vy.data(), v.vz = store.vz.data();
  v.w = store.w.data();
  v.phase = store.phase.data();
  return v;
}

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

template <class T>
AlignedColumn<T>& ParticleStore::spare_column() {
  if constexpr (std::is_same_v<T, float>) return spare_float_;
  else if constexpr (std::is_same_v<T, std::uint32_t>) return spare_uint_;
  else return spare_int_;
}

void ParticleStore::reorder(std::span<const std::uint32_t> order) {
  const std::size_t n = size_;
  // Gather each column into the spare of its type, then swap the buffers (no copy back). Both
  // have the same padded length and zero padding (the gather writes only [0, n)).
  for_each_state_column([&](auto& column) {
    using T = std::remove_reference_t<decltype(column[0])>;
    AlignedColumn<T>& spare = spare_column<T>();
    spare.resize(n);
    const T* src = column.data();
    T* dst = spare.data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t k = r.begin(); k != r.end(); ++k) dst[k] = src[order[k]];
                      });
    column.storage().swap(spare.storage());
  });
}

std::vector<std::uint32_t> ParticleStore::index_of_id() const {
  std::vector<std::uint32_t> index(size_);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, size_, 16384), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) index[std::size_t(id[i])] = std::uint32_t(i);
  });  // ids are distinct: no two writes meet
  return index;
}

std::size_t ParticleStore::bytes() const {
  std::size_t b = 0;
  for (const FloatColumn* c : {&x, &y, &z, &px, &py, &pz, &vx, &vy, &vz, &w, &density, &lambda,
                               &omega_x, &omega_y, &omega_z, &spare_float_})
    b += c->bytes();
  return b + phase.bytes() + id.bytes() + spare_uint_.bytes() + spare_int_.bytes();
}

std::vector<std::uint32_t> inverse_permutation(std::span<const std::uint32_t> order) {
  std::vector<std::uint32_t> inv(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) inv[order[k]] = std::uint32_t(k);
  return inv;
}

}  // namespace seiche
