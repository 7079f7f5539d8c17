#include "seiche/state_hash.hpp"

#include <bit>
#include <vector>

namespace seiche {

namespace {

constexpr std::uint64_t kFnvOffsetBasis = 0xcbf29ce484222325ull;
constexpr std::uint64_t kFnvPrime = 0x100000001b3ull;

// One value's bytes, least significant first.
template <typename Bits, typename Value>
std::uint64_t hash_bits(std::uint64_t h, Value value) {
  const Bits bits = std::bit_cast<Bits>(value);
  for (std::size_t byte = 0; byte < sizeof(Bits); ++byte) {
    h ^= (bits >> (8 * byte)) & 0xffu;
    h *= kFnvPrime;
  }
  return h;
}
std::uint64_t hash_float(std::uint64_t h, float value) { return hash_bits<std::uint32_t>(h, value); }
std::uint64_t hash_double(std::uint64_t h, double value) { return hash_bits<std::uint64_t>(h, value); }

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

std::uint64_t body_state_hash(std::span<const BodyPose> bodies) {
  std::uint64_t h = kFnvOffsetBasis;
  for (const BodyPose& b : bodies) {
    for (const double v : b.position) h = hash_double(h, v);
    for (const double v : b.orientation) h = hash_double(h, v);
    for (const double v : b.velocity) h = hash_double(h, v);
    for (const double v : b.angular_velocity) h = hash_double(h, v);
  }
  return h;
}

}  // namespace seiche
