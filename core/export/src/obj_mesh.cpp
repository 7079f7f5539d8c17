// OBJ mesh of a level set: see obj_mesh.hpp. Normals are the normalized central difference of
// the trilinearly interpolated level set at the vertex (half a voxel either side); a vanishing
// gradient (not on a proper level set) falls back to +y rather than dividing by zero. Numbers are
// written in fixed point (positions to 1e-6, normals to 1e-4) by integer formatting: the text is
// the bulk of the cost, and this is several times faster than a general float formatter.
#include "obj_mesh.hpp"

#include <fmt/format.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace seiche::exporting {
namespace {

void append_int(std::string& out, std::uint64_t value) {
  char digits[24];
  const auto end = std::to_chars(digits, digits + sizeof digits, value).ptr;
  out.append(digits, end);
}

/// value rounded to `decimals` (<= 9) digits after the point; never "-0.000".
void append_fixed(std::string& out, double value, int decimals, std::uint64_t scale) {
  const double scaled = std::nearbyint(value * double(scale));
  if (!std::isfinite(scaled) ||
      std::abs(scaled) > 9e15) {  // not on a proper level set; keep the file valid
    out += '0';
    return;
  }
  std::int64_t q = std::int64_t(scaled);
  if (q < 0) out += '-', q = -q;
  append_int(out, std::uint64_t(q) / scale);
  out += '.';
  char frac[16];
  std::uint64_t f = std::uint64_t(q) % scale;
  for (int d = decimals - 1; d >= 0; --d) frac[d] = char('0' + f % 10), f /= 10;
  out.append(frac, std::size_t(decimals));
}

void append_vector(std::string& out, const char* tag, const openvdb::Vec3s& v, int decimals,
                   std::uint64_t scale) {
  out += tag;
  for (int a = 0; a < 3; ++a) {
    out += ' ';
    append_fixed(out, double(v[a]), decimals, scale);
  }
  out += '\n';
}

}  // namespace

std::string encode_obj_mesh(const openvdb::FloatGrid& surface, std::string_view header) {
  std::vector<openvdb::Vec3s> vertices;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(surface, vertices, quads, 0.0);

  std::vector<openvdb::Vec3s> normals(vertices.size());
  const double h = 0.5 * surface.voxelSize()[0];
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, vertices.size(), 1024),
      [&](const tbb::blocked_range<std::size_t>& r) {
        const openvdb::FloatGrid::ConstAccessor acc = surface.getConstAccessor();
        const openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor,
                                          openvdb::tools::BoxSampler>
            phi(acc, surface.transform());
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const openvdb::Vec3d p(vertices[i]);
          openvdb::Vec3d g(
              phi.wsSample(p + openvdb::Vec3d(h, 0, 0)) - phi.wsSample(p - openvdb::Vec3d(h, 0, 0)),
              phi.wsSample(p + openvdb::Vec3d(0, h, 0)) - phi.wsSample(p - openvdb::Vec3d(0, h, 0)),
              phi.wsSample(p + openvdb::Vec3d(0, 0, h)) -
                  phi.wsSample(p - openvdb::Vec3d(0, 0, h)));
          const double length = g.length();
          normals[i] = length > 1e-12 ? openvdb::Vec3s(g / length) : openvdb::Vec3s(0, 1, 0);
        }
      });

  std::string out =
      fmt::format("# {}\n# {} vertices, {} quads\n", header, vertices.size(), quads.size());
  out.reserve(out.size() + 36 * vertices.size() + 30 * normals.size() + 40 * quads.size());
  for (const auto& v : vertices) append_vector(out, "v", v, 6, 1000000);
  for (const auto& n : normals) append_vector(out, "vn", n, 4, 10000);
  // volumeToMesh winds quads clockwise seen from outside a level set (negative inside); OBJ wants
  // counter-clockwise, so the order is reversed.
  for (const auto& q : quads) {
    out += 'f';
    for (int k = 3; k >= 0; --k) {
      out += ' ';
      append_int(out, std::uint64_t(q[k]) + 1);
      out += "//";
      append_int(out, std::uint64_t(q[k]) + 1);
    }
    out += '\n';
  }
  return out;
}

}  // namespace seiche::exporting
