#include "seiche/state_hash.hpp"

#include <bit>
#include <vector>

namespace seiche {

namespace {

constexpr std::uint64_t kFnvOffsetBasis = 0xcbf29ce484222325ull;
constexpr std::uint64_t kFnvPrime = 0x100000001b3ull;

// One value's 4 bytes, least significant first.
std::uint64_t hash_float(std::uint64_t h, float value) {
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(value);
  for (int byte = 0; byte < 4; ++byte) {
    h ^= (bits >> (8 * byte)) & 0xffu;
    h *= kFnvPrime;
  }
  return h;
}

}  // namespace

std::uint64_t state_hash(const ParticleStore& store) {
  const std::vector<std::uint32_t> index_of_id = store.index_of_id();
  std::uint64_t h = kFnvOffsetBasis;
  for (const std::uint32_t i : index_of_id)
    for (const float v :
         {store.x[i], store.y[i], store.z[i], store.vx[i], store.vy[i], store.vz[i]})
      h = hash_float(h, v);
  return h;
}

}  // namespace seiche
