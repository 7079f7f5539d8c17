// The particles in VTK's XML formats (vtk_particles.hpp): a .vtp per frame and the .pvd series.
//
// Written by hand: a .vtp is a short XML header and four raw arrays, and linking VTK for that
// would be a heavy dependency (hundreds of MB of libraries, a second copy of what ParaView
// already ships) in a core that links nothing but TBB, fmt and JSON.
//
// Encoding: appended raw binary, header_type="UInt64", byte_order="LittleEndian". The XML header
// names each array with its offset into <AppendedData>; there every array is a UInt64 byte count
// followed by its bytes. Raw rather than inline base64: the file is as small as the data (base64
// adds a third), it is written with memcpy at memory speed (no encoding pass), and every VTK XML
// reader reads it (ParaView, VisIt, VTK's Python). The price: past the `_` that opens the
// appended data the file is not text, so a plain XML parser reads the header only (the readers
// of the tests split the file there). UInt64 block headers: an array over 4 GiB (more than 350
// million particles) stays valid.
//
// Layout of a frame of n particles, in id order (the PLY's order):
//   PointData  velocity      Float32 x3   vx vy vz (m/s)
//              id            Int32        the store's id column (creation index)
//   Points     Points        Float32 x3   x y z (m)
//   Verts      connectivity  Int32        0 .. n-1
//              offsets       Int32        1 .. n
// Verts make every point a vertex cell: without cells ParaView's default representation draws
// nothing. Int32 suffices (ids are int32, so n < 2^31); VTK converts them to its id type.
#include "seiche/vtk_particles.hpp"

#include <bit>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "seiche/output_files.hpp"

namespace seiche {

namespace {

static_assert(std::endian::native == std::endian::little, "the .vtp writer declares LittleEndian");

// One array of the appended data: its bytes per particle; its offset follows from the ones before.
struct Block {
  std::size_t bytes_per_particle;
  std::uint64_t offset = 0;  // from the first byte after the `_`
  std::uint64_t size(std::size_t n) const { return sizeof(std::uint64_t) + bytes_per_particle * n; }
};

}  // namespace

std::string encode_particles_vtp(const ParticleStore& s) {
  const std::size_t n = s.size();
  // In the order of the appended data.
  Block velocity{3 * sizeof(float)}, id{sizeof(std::int32_t)}, points{3 * sizeof(float)},
      connectivity{sizeof(std::int32_t)}, offsets{sizeof(std::int32_t)};
  Block* blocks[] = {&velocity, &id, &points, &connectivity, &offsets};
  std::uint64_t end = 0;
  for (Block* b : blocks) {
    b->offset = end;
    end += b->size(n);
  }

  std::string out = fmt::format(
      "<?xml version=\"1.0\"?>\n"
      "<!-- written by seiche -->\n"
      "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      "  <PolyData>\n"
      "    <Piece NumberOfPoints=\"{0}\" NumberOfVerts=\"{0}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
      "NumberOfPolys=\"0\">\n"
      "      <PointData Scalars=\"id\" Vectors=\"velocity\">\n"
      "        <DataArray type=\"Float32\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"appended\" "
      "offset=\"{1}\"/>\n"
      "        <DataArray type=\"Int32\" Name=\"id\" format=\"appended\" offset=\"{2}\"/>\n"
      "      </PointData>\n"
      "      <Points>\n"
      "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" "
      "offset=\"{3}\"/>\n"
      "      </Points>\n"
      "      <Verts>\n"
      "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"{4}\"/>\n"
      "        <DataArray type=\"Int32\" Name=\"offsets\" format=\"appended\" offset=\"{5}\"/>\n"
      "      </Verts>\n"
      "    </Piece>\n"
      "  </PolyData>\n"
      "  <AppendedData encoding=\"raw\">\n"
      "   _",
      n, velocity.offset, id.offset, points.offset, connectivity.offset, offsets.offset);
  static constexpr std::string_view kTail = "\n  </AppendedData>\n</VTKFile>\n";
  const std::size_t data = out.size();
  out.resize(data + end + kTail.size());
  char* const base = out.data() + data;
  for (const Block* b : blocks) {
    const std::uint64_t payload = b->bytes_per_particle * n;
    std::memcpy(base + b->offset, &payload, sizeof(payload));
  }
  std::memcpy(base + end, kTail.data(), kTail.size());

  // The store is in cell order, exports are in id order.
  const std::vector<std::uint32_t> index_of_id = s.index_of_id();
  auto at = [&](const Block& b, std::size_t k) { return base + b.offset + sizeof(std::uint64_t) + k * b.bytes_per_particle; };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::uint32_t i = index_of_id[k];
      const float x[3] = {s.x[i], s.y[i], s.z[i]};
      const float v[3] = {s.vx[i], s.vy[i], s.vz[i]};
      const std::int32_t vertex = std::int32_t(k), vertex_end = std::int32_t(k + 1);
      std::memcpy(at(velocity, k), v, sizeof(v));
      std::memcpy(at(id, k), &s.id[i], sizeof(std::int32_t));
      std::memcpy(at(points, k), x, sizeof(x));
      std::memcpy(at(connectivity, k), &vertex, sizeof(vertex));
      std::memcpy(at(offsets, k), &vertex_end, sizeof(vertex_end));
    }
  });
  return out;
}

std::string encode_particle_series_pvd(std::string_view stem, int first_frame, int last_frame, double frame_dt) {
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out),
                 "<?xml version=\"1.0\"?>\n"
                 "<!-- written by seiche: the frames of {}.%04d.vtp with their simulated times (s) -->\n"
                 "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
                 "  <Collection>\n",
                 stem);
  for (std::int64_t f = first_frame; f <= last_frame; ++f)  // 64 bits: last_frame may be INT_MAX
    fmt::format_to(std::back_inserter(out), "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n",
                   double(f) * frame_dt, frame_file_name(stem, int(f), "vtp"));
  fmt::format_to(std::back_inserter(out), "  </Collection>\n</VTKFile>\n");
  return fmt::to_string(out);
}

}  // namespace seiche
