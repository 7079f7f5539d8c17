// .vdb bytes with a reproducible header: see vdb_file.hpp.
//
// OpenVDB's header (io::Archive::writeHeader, file format 224): magic (8 bytes), file format
// version (4), library major and minor version (4 + 4), "has grid offsets" (1), then the UUID as
// 36 ASCII characters. The UUID is checked to be where the format puts it before it is replaced.
#include "vdb_file.hpp"

#include <fmt/format.h>
#include <openvdb/io/Stream.h>

#include <array>
#include <cstdio>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace seiche::exporting {
namespace {

constexpr std::size_t kUuidOffset = 8 + 4 + 4 + 4 + 1;
constexpr std::size_t kUuidLength = 36;

bool looks_like_uuid(std::string_view s) {
  if (s.size() != kUuidLength) return false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
    const char c = s[i];
    if (dash ? c != '-'
             : !((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F')))
      return false;
  }
  return true;
}

/// FNV-1a 64 of `text`, started from `seed`.
std::uint64_t fnv1a(std::string_view text, std::uint64_t seed) {
  std::uint64_t h = seed;
  for (const char c : text) h = (h ^ std::uint8_t(c)) * 0x100000001b3ull;
  return h;
}

/// splitmix64 finaliser: spreads the hash over all bits.
std::uint64_t mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

}  // namespace

void initialize_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

VdbCompression parse_vdb_compression(std::string_view name) {
  if (name == "blosc") return VdbCompression::Blosc;
  if (name == "zip") return VdbCompression::Zip;
  if (name == "none") return VdbCompression::None;
  throw std::invalid_argument(
      fmt::format("compression \"{}\" is not one of \"blosc\", \"zip\", \"none\"", name));
}

std::uint32_t vdb_compression_flags(VdbCompression c) {
  namespace io = openvdb::io;
  switch (c) {
    case VdbCompression::Blosc:
      if (io::Archive::hasBloscCompression()) return io::COMPRESS_BLOSC | io::COMPRESS_ACTIVE_MASK;
      {
        static std::once_flag note;
        std::call_once(note, [] {
          std::fputs(
              "seiche: note: this OpenVDB library has no Blosc; .vdb files use zip compression\n",
              stderr);
        });
      }
      return io::COMPRESS_ZIP | io::COMPRESS_ACTIVE_MASK;
    case VdbCompression::Zip:
      return io::COMPRESS_ZIP | io::COMPRESS_ACTIVE_MASK;
    case VdbCompression::None:
      return io::COMPRESS_NONE;
  }
  return io::COMPRESS_NONE;
}

std::string deterministic_uuid(std::string_view identity) {
  const std::uint64_t hi = mix(fnv1a(identity, 0xcbf29ce484222325ull));
  const std::uint64_t lo = mix(fnv1a(identity, hi ^ 0x9e3779b97f4a7c15ull));
  // RFC 9562 layout: version 8 (custom) and variant 10xx, so it never collides with a random (v4)
  // UUID.
  const std::uint64_t a = (hi & 0xffffffffffff0fffull) | 0x0000000000008000ull;
  const std::uint64_t b = (lo & 0x3fffffffffffffffull) | 0x8000000000000000ull;
  return fmt::format("{:08x}-{:04x}-{:04x}-{:04x}-{:012x}", a >> 32, (a >> 16) & 0xffff, a & 0xffff,
                     b >> 48, b & 0xffffffffffffull);
}

std::string encode_vdb_file(const openvdb::GridCPtrVec& grids, const openvdb::MetaMap& metadata,
                            VdbCompression compression, std::string_view identity) {
  initialize_openvdb();
  std::ostringstream bytes(std::ios_base::out | std::ios_base::binary);
  openvdb::io::Stream stream(bytes);
  stream.setCompression(vdb_compression_flags(compression));
  stream.write(grids, metadata);
  std::string out = std::move(bytes).str();
  if (out.size() < kUuidOffset + kUuidLength ||
      !looks_like_uuid(std::string_view(out).substr(kUuidOffset, kUuidLength)))
    throw std::logic_error(
        "encode_vdb_file: OpenVDB's header has no UUID where file format 224 puts it");
  out.replace(kUuidOffset, kUuidLength, deterministic_uuid(identity));
  return out;
}

}  // namespace seiche::exporting
