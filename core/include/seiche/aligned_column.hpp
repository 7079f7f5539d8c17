// A column of the particle store: a 64-byte aligned array whose storage is padded to a whole
// number of 64-byte blocks (16 floats), so that SIMD kernels may load full batches at the end
// of the array. The padding is value-initialized (zero) and never part of size().
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

namespace seiche {

inline constexpr std::size_t kColumnAlignment = 64;   // bytes: a cache line, an AVX-512 register
inline constexpr std::size_t kColumnPadding = 16;     // elements of 4 bytes per 64 bytes

constexpr std::size_t padded_count(std::size_t n) {
  return (n + kColumnPadding - 1) / kColumnPadding * kColumnPadding;
}

template <class T>
struct AlignedAllocator {
  using value_type = T;
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  T* allocate(std::size_t n) {
    std::size_t bytes = (n * sizeof(T) + kColumnAlignment - 1) / kColumnAlignment * kColumnAlignment;
    void* p = std::aligned_alloc(kColumnAlignment, bytes == 0 ? kColumnAlignment : bytes);
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t) noexcept { std::free(p); }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const { return true; }
};

template <class T>
class AlignedColumn {
 public:
  void resize(std::size_t n) {
    size_ = n;
    data_.resize(padded_count(n), T{});
  }
  /// Room for n elements (padded): a later resize(m <= n) does not reallocate.
  void reserve(std::size_t n) { data_.reserve(padded_count(n)); }
  void clear_storage() {
    size_ = 0;
    data_ = {};
  }
  bool allocated() const { return !data_.empty(); }
  std::size_t size() const { return size_; }
  std::size_t bytes() const { return data_.capacity() * sizeof(T); }
  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  std::vector<T, AlignedAllocator<T>>& storage() { return data_; }

 private:
  std::size_t size_ = 0;
  std::vector<T, AlignedAllocator<T>> data_;
};

}  // namespace seiche
