// Named byte chunks: the state a constraint family carries from one substep to the next beyond
// the store's State columns (the cloth stretch forests' multipliers, say), as it goes into a
// checkpoint (checkpoint.hpp). A family writes its chunks under names that begin with its own
// ("cloth.stretch_multipliers") and reads them back into a family built from the same scene,
// checking their sizes; the file holds them by name, so a new family needs no format change.
#pragma once

#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace seiche {

class CheckpointChunks {
 public:
  struct Chunk {
    std::string name;
    std::string bytes;
  };

  /// Adds a chunk. Throws std::invalid_argument when the name is taken.
  void put(std::string name, std::string bytes);
  template <class T>
  void put_values(std::string name, std::span<const T> values) {
    static_assert(std::is_trivially_copyable_v<T>);
    put(std::move(name), std::string(reinterpret_cast<const char*>(values.data()), values.size_bytes()));
  }

  /// The chunk called `name`, or null.
  const Chunk* find(std::string_view name) const;
  /// The bytes of chunk `name`, which must hold exactly `size` bytes. Throws ResumeError
  /// (checkpoint.hpp; restore_checkpoint adds the file's name) when it is missing or of
  /// another size.
  std::string_view get(std::string_view name, std::size_t size) const;
  /// Fills `values` from chunk `name`, which must hold exactly values.size() of them.
  template <class T>
  void get_values(std::string_view name, std::span<T> values) const {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::string_view bytes = get(name, values.size_bytes());
    if (!bytes.empty()) std::memcpy(values.data(), bytes.data(), bytes.size());
  }

  /// Every chunk, in the order they were put.
  const std::vector<Chunk>& all() const { return chunks_; }

 private:
  std::vector<Chunk> chunks_;
};

}  // namespace seiche
