// Writing .vdb files byte-for-byte reproducibly. OpenVDB's stream writer puts a random UUID in
// every file header; we replace it with one derived from the file's identity (scene name and
// frame), so the same frame always gives the same bytes: a resumed bake rewrites a frame
// identically, and a file compares equal to its earlier self.
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>
#include <string>
#include <string_view>

namespace seiche::exporting {

enum class VdbCompression { Blosc, Zip, None };

/// "blosc", "zip" or "none"; throws std::invalid_argument naming the accepted values.
VdbCompression parse_vdb_compression(std::string_view name);

/// OpenVDB's compression flags for `c`. Blosc falls back to zip (with a one-line note on stderr,
/// once) when the OpenVDB library was built without Blosc. Note that OpenVDB never zips level
/// sets and fog volumes (their inactive values are dropped instead); Blosc applies to all grids.
std::uint32_t vdb_compression_flags(VdbCompression c);

/// A UUID-formatted (8-4-4-4-12 hex digits) name-based identifier of `identity`.
std::string deterministic_uuid(std::string_view identity);

/// The bytes of a .vdb file holding `grids` and the file-level `metadata`, written with
/// openvdb::io::Stream, with its header UUID set to deterministic_uuid(identity).
std::string encode_vdb_file(const openvdb::GridCPtrVec& grids, const openvdb::MetaMap& metadata,
                            VdbCompression compression, std::string_view identity);

/// Calls openvdb::initialize() once per process.
void initialize_openvdb();

}  // namespace seiche::exporting
