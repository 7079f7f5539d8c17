#include "seiche/particle_store.hpp"

#include <algorithm>
#include <iterator>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <tbb/parallel_for.h>

namespace seiche {

const char* column_type_name(ColumnType type) {
  switch (type) {
    case ColumnType::F32: return "f32";
    case ColumnType::U32: return "u32";
    case ColumnType::I32: return "i32";
  }
  return "?";
}

const char* StoreColumn::raw() const {
  return std::visit([](const auto& c) { return reinterpret_cast<const char*>(c.data()); }, data);
}

char* StoreColumn::raw() {
  return std::visit([](auto& c) { return reinterpret_cast<char*>(c.data()); }, data);
}

kernels::ParticleView particle_view(ParticleStore& store) {
  kernels::ParticleView v;
  v.n = store.size();
  v.x = store.x.data(), v.y = store.y.data(), v.z = store.z.data();
  v.px = store.px.data(), v.py = store.py.data(), v.pz = store.pz.data();
  v.vx = store.vx.data(), v.vy = store.vy.data(), v.vz = store.vz.data();
  v.w = store.w.data();
  v.radius = store.radius.data();
  return v;
}

// Each store declares the built-ins in the same order, so a copy's table and this one's agree on
// the position of every named member; assigning column by column keeps them where they are
// (a deque keeps its elements' addresses when it grows or shrinks at the end).
ParticleStore::ParticleStore() = default;

ParticleStore::ParticleStore(const ParticleStore& other) : columns_(other.columns_), size_(other.size_) {}

ParticleStore::ParticleStore(ParticleStore&& other) noexcept
    : columns_(std::make_move_iterator(other.columns_.begin()), std::make_move_iterator(other.columns_.end())),
      size_(std::exchange(other.size_, 0)) {}

ParticleStore& ParticleStore::operator=(const ParticleStore& other) {
  if (this == &other) return *this;
  columns_.resize(other.columns_.size());
  std::copy(other.columns_.begin(), other.columns_.end(), columns_.begin());
  size_ = other.size_;
  return *this;
}

ParticleStore& ParticleStore::operator=(ParticleStore&& other) noexcept {
  if (this == &other) return *this;
  columns_.resize(other.columns_.size());
  std::move(other.columns_.begin(), other.columns_.end(), columns_.begin());
  size_ = std::exchange(other.size_, 0);
  return *this;
}

template <class T>
AlignedColumn<T>& ParticleStore::declare(const char* name, ColumnKind kind, bool enabled) {
  if (StoreColumn* c = find(name)) return std::get<AlignedColumn<T>>(c->data);
  columns_.push_back({name, kind, enabled, AlignedColumn<T>()});
  return std::get<AlignedColumn<T>>(columns_.back().data);
}

template <class T>
AlignedColumn<T>& ParticleStore::add_column(std::string name, ColumnKind kind) {
  if (find(name) != nullptr)
    throw std::invalid_argument("ParticleStore::add_column: a column '" + name + "' exists already");
  columns_.push_back({std::move(name), kind, true, AlignedColumn<T>()});
  auto& column = std::get<AlignedColumn<T>>(columns_.back().data);
  column.reserve(std::max(reserved_, size_));
  column.resize(size_);
  return column;
}
template FloatColumn& ParticleStore::add_column<float>(std::string, ColumnKind);
template AlignedColumn<std::uint32_t>& ParticleStore::add_column<std::uint32_t>(std::string, ColumnKind);
template AlignedColumn<std::int32_t>& ParticleStore::add_column<std::int32_t>(std::string, ColumnKind);

const StoreColumn* ParticleStore::find(std::string_view name) const {
  for (const StoreColumn& c : columns_)
    if (c.name == name) return &c;
  return nullptr;
}

StoreColumn* ParticleStore::find(std::string_view name) {
  return const_cast<StoreColumn*>(std::as_const(*this).find(name));
}

void ParticleStore::resize(std::size_t n) {
  size_ = n;
  for (StoreColumn& c : columns_)
    if (c.enabled) std::visit([n](auto& column) { column.resize(n); }, c.data);
}

void ParticleStore::reserve(std::size_t n) {
  reserved_ = n;
  for (StoreColumn& c : columns_)
    if (c.enabled) std::visit([n](auto& column) { column.reserve(n); }, c.data);
}

void ParticleStore::enable(FloatColumn& column) {
  for (StoreColumn& c : columns_)
    if (std::get_if<FloatColumn>(&c.data) == &column) c.enabled = true;
  column.reserve(std::max(reserved_, size_));
  column.resize(size_);
}

void ParticleStore::enable_fluid_columns() {
  enable(density);
  enable(lambda);
}

void ParticleStore::enable_vorticity_columns() {
  enable(omega_x);
  enable(omega_y);
  enable(omega_z);
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
  for (StoreColumn& c : columns_) {
    if (c.kind == ColumnKind::Scratch) continue;
    std::visit(
        [&](auto& column) {
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
        },
        c.data);
  }
}

std::vector<std::uint32_t> ParticleStore::index_of_id() const {
  std::vector<std::uint32_t> index(size_);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, size_, 16384), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) index[std::size_t(id[i])] = std::uint32_t(i);
  });  // ids are distinct: no two writes meet
  return index;
}

std::size_t ParticleStore::bytes() const {
  std::size_t b = spare_float_.bytes() + spare_uint_.bytes() + spare_int_.bytes();
  for (const StoreColumn& c : columns_) b += std::visit([](const auto& column) { return column.bytes(); }, c.data);
  return b;
}

std::vector<std::uint32_t> inverse_permutation(std::span<const std::uint32_t> order) {
  std::vector<std::uint32_t> inv(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) inv[order[k]] = std::uint32_t(k);
  return inv;
}

}  // namespace seiche
