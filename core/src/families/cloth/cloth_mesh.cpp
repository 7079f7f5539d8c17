// A cloth's triangle mesh (contract in cloth_mesh.hpp):
//
// - make_sheet: a regular grid of vertices, each cell cut into two triangles along a diagonal
//   that alternates in a checkerboard (so the sheet has no preferred shear direction). Every
//   triangle is wound so that its normal points along the positive third axis (+y for "xz" and
//   "zx", +z for "xy", +x for "yz"), whatever the order of the plane's letters.
// - read_obj_mesh: the file is first checked line by line ("v", "vt" and "f" lines must be well
//   formed: tinyobjloader silently reads "abc" as 0), then loaded by tinyobjloader without
//   triangulation. The polygons are kept for output and fanned, (c0, ci, ci+1), into the
//   simulated triangles; degenerate triangles (a repeated vertex, or an area below 1e-12 of the
//   mesh's mean squared edge length) are left out with a warning.
// - build_topology: every triangle edge becomes a (min, max, triangle) record; sorting the
//   records groups each edge's triangles, which gives the edges, the hinges (edges with two
//   triangles) and the non-manifold check in one pass. Adjacency is a sorted CSR list.
// - encode_cloth_obj: OBJ text written with std::to_chars into one buffer (the shortest float
//   text that reads back to the same float: at most 9 significant digits).
#include "cloth_mesh.hpp"

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <system_error>

#include "seiche/checkpoint.hpp"
#include "seiche/scene_loader.hpp"

namespace seiche {
namespace {

namespace fs = std::filesystem;

using Tri = std::array<std::uint32_t, 3>;

// Area of a triangle and the sum of its squared edge lengths, in double.
double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double ux = double(b[0]) - a[0], uy = double(b[1]) - a[1], uz = double(b[2]) - a[2];
  const double vx = double(c[0]) - a[0], vy = double(c[1]) - a[1], vz = double(c[2]) - a[2];
  const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
  return 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
}

double squared_distance(const Vec3& a, const Vec3& b) {
  const double x = double(b[0]) - a[0], y = double(b[1]) - a[1], z = double(b[2]) - a[2];
  return x * x + y * y + z * z;
}

// "4, 9, 12" for up to `max_listed` numbers, then ", ..." if there are more.
std::string list_numbers(const std::vector<std::size_t>& numbers, std::size_t max_listed = 5) {
  std::string s;
  for (std::size_t i = 0; i < numbers.size() && i < max_listed; ++i) {
    if (i > 0) s += ", ";
    s += std::to_string(numbers[i]);
  }
  if (numbers.size() > max_listed) s += ", ...";
  return s;
}

// ---- OBJ syntax check --------------------------------------------------------------------------

// What the strict pass over the "v", "vt" and "f" lines learns besides "it is well formed".
struct ObjScan {
  std::vector<std::size_t> face_line;  ///< 1-based line of each face, in file order
};

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

std::vector<std::string_view> split_tokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !is_blank(line[j])) ++j;
    if (j > i) tokens.push_back(line.substr(i, j - i));
    i = j;
  }
  return tokens;
}

// Parses a whole token as a number; false if it is not one (or has trailing characters).
bool parse_number(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec == std::errc::result_out_of_range) {
    value = std::numeric_limits<double>::infinity();
    return end == token.data() + token.size();
  }
  return ec == std::errc() && end == token.data() + token.size();
}

bool parse_index(std::string_view token, long& value) {
  if (token.empty()) return false;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

// Throws the malformed-file error for line `line`.
[[noreturn]] void malformed(const std::string& file, const std::string& json_path, std::size_t line,
                            const std::string& what) {
  throw SceneError(file, json_path, fmt::format("malformed OBJ, line {}: {}", line, what));
}

ObjScan scan_obj(std::string_view text, const std::string& file, const std::string& json_path) {
  ObjScan scan;
  std::size_t line_number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;

    // Tokens before a '#' (a comment, also at the end of a line).
    const std::vector<std::string_view> tokens = split_tokens(line.substr(0, line.find('#')));
    if (tokens.empty()) continue;
    const std::string_view key = tokens[0];
    const std::size_t args = tokens.size() - 1;
    if (key == "v" || key == "vt") {
      const bool position = key == "v";
      // "v x y z [w]" or "v x y z r g b"; "vt u [v [w]]".
      if (position ? (args < 3 || args > 7) : (args < 1 || args > 3)) {
        malformed(file, json_path, line_number,
                  position ? fmt::format("a vertex needs 3 coordinates, got {}", args)
                           : fmt::format("a texture coordinate needs 1 to 3 values, got {}", args));
      }
      for (std::size_t t = 1; t < tokens.size(); ++t) {
        double value = 0.0;
        if (!parse_number(tokens[t], value)) {
          malformed(file, json_path, line_number,
                    fmt::format("'{}' is not a number", std::string(tokens[t])));
        }
        const bool checked = position ? t <= 3 : t <= 2;
        if (checked && !(std::isfinite(value) && std::abs(value) <= std::numeric_limits<float>::max())) {
          throw SceneError(file, json_path,
                           fmt::format("line {}: non-finite coordinate '{}'", line_number,
                                       std::string(tokens[t])));
        }
      }
    } else if (key == "f") {
      if (args < 3) {
        malformed(file, json_path, line_number,
                  fmt::format("a face needs at least 3 corners, got {}", args));
      }
      if (args > 255) {  // tinyobjloader counts a face's corners in an unsigned char
        malformed(file, json_path, line_number,
                  fmt::format("a face with {} corners (at most 255 are supported)", args));
      }
      for (std::size_t t = 1; t < tokens.size(); ++t) {
        // v, v/vt, v//vn or v/vt/vn; each index a non-zero integer (negative: relative).
        const std::string_view corner = tokens[t];
        std::vector<std::string_view> parts;  // split at '/'
        for (std::size_t start = 0;;) {
          const std::size_t slash = corner.find('/', start);
          parts.push_back(corner.substr(start, slash == std::string_view::npos ? slash : slash - start));
          if (slash == std::string_view::npos) break;
          start = slash + 1;
        }
        bool ok = parts.size() <= 3;
        for (std::size_t p = 0; ok && p < parts.size(); ++p) {
          if (p == 1 && parts.size() == 3 && parts[1].empty()) continue;  // v//vn
          long index = 0;
          ok = parse_index(parts[p], index) && index != 0;
        }
        if (!ok) {
          malformed(file, json_path, line_number,
                    fmt::format("'{}' is not a face corner (v, v/vt, v//vn or v/vt/vn with "
                                "indices counted from 1)",
                                std::string(corner)));
        }
      }
      scan.face_line.push_back(line_number);
    }
  }
  return scan;
}

// tinyobjloader asks this for "mtllib" files: materials are ignored, so nothing is read.
class NoMaterials : public tinyobj::MaterialReader {
 public:
  bool operator()(const std::string&, std::vector<tinyobj::material_t>*,
                  std::map<std::string, int>*, std::string*, std::string*) override {
    return true;
  }
};

std::string trim_message(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ' || s.back() == '.'))
    s.pop_back();
  for (char& c : s) {
    if (c == '\n') c = ' ';
  }
  return s;
}

}  // namespace

// ---- make_sheet --------------------------------------------------------------------------------

ClothMesh make_sheet(const SheetDef& sheet, const std::string& file, const std::string& json_path) {
  const int r0 = sheet.resolution[0], r1 = sheet.resolution[1];
  for (int r : {r0, r1}) {
    if (r < 2 || r > 4096) {
      throw SceneError(file, json_path + ".resolution",
                       fmt::format("vertices per side must be in 2..4096, got [{}, {}]", r0, r1));
    }
  }
  for (float s : sheet.size) {
    if (!(s > 0.0f) || !std::isfinite(s)) {
      throw SceneError(file, json_path + ".size",
                       fmt::format("must be > 0 (m), got [{}, {}]", sheet.size[0], sheet.size[1]));
    }
  }
  const std::string& plane = sheet.plane;
  auto axis_of = [](char c) { return c == 'x' ? 0 : c == 'y' ? 1 : c == 'z' ? 2 : -1; };
  if (plane.size() != 2 || axis_of(plane[0]) < 0 || axis_of(plane[1]) < 0 || plane[0] == plane[1]) {
    throw SceneError(file, json_path + ".plane",
                     fmt::format("must be two distinct axes of x, y, z (\"xz\", \"xy\", ...), got "
                                 "\"{}\"",
                                 plane));
  }
  const int a0 = axis_of(plane[0]), a1 = axis_of(plane[1]);
  // e_a0 x e_a1 is -e_third when (a0, a1) is not in cyclic order (x->y->z->x): then the triangles
  // are wound the other way so that the normal still points along +third axis.
  const bool flip = (a1 - a0 + 3) % 3 == 2;

  ClothMesh mesh;
  const std::size_t n = std::size_t(r0) * std::size_t(r1);
  mesh.positions.resize(n);
  mesh.texcoords.resize(n);
  for (int j = 0; j < r1; ++j) {
    for (int i = 0; i < r0; ++i) {
      const std::size_t v = std::size_t(j) * std::size_t(r0) + std::size_t(i);
      Vec3 p = sheet.origin;
      p[a0] = float(double(sheet.origin[a0]) + double(sheet.size[0]) * i / (r0 - 1));
      p[a1] = float(double(sheet.origin[a1]) + double(sheet.size[1]) * j / (r1 - 1));
      mesh.positions[v] = p;
      mesh.texcoords[v] = {float(double(i) / (r0 - 1)), float(double(j) / (r1 - 1))};
    }
  }

  mesh.triangles.reserve(2 * std::size_t(r0 - 1) * std::size_t(r1 - 1));
  auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    mesh.triangles.push_back(flip ? Tri{a, c, b} : Tri{a, b, c});
  };
  for (int j = 0; j + 1 < r1; ++j) {
    for (int i = 0; i + 1 < r0; ++i) {
      const auto v00 = std::uint32_t(j * r0 + i), v10 = v00 + 1;
      const auto v01 = v00 + std::uint32_t(r0), v11 = v01 + 1;
      if ((i + j) % 2 == 0) {  // diagonal v00-v11
        add(v00, v10, v11);
        add(v00, v11, v01);
      } else {  // diagonal v10-v01
        add(v00, v10, v01);
        add(v10, v11, v01);
      }
    }
  }

  // Faces for output are the triangles; a vertex's texcoord has the vertex's index.
  const std::size_t t = mesh.triangles.size();
  mesh.face_start.resize(t + 1);
  mesh.corner_vertex.resize(3 * t);
  mesh.corner_texcoord.resize(3 * t);
  for (std::size_t f = 0; f <= t; ++f) mesh.face_start[f] = std::uint32_t(3 * f);
  for (std::size_t f = 0; f < t; ++f) {
    for (int k = 0; k < 3; ++k) {
      mesh.corner_vertex[3 * f + k] = mesh.triangles[f][k];
      mesh.corner_texcoord[3 * f + k] = std::int32_t(mesh.triangles[f][k]);
    }
  }
  return mesh;
}

// ---- read_obj_mesh -----------------------------------------------------------------------------

ClothMesh read_obj_mesh(const fs::path& obj_file, const ClothMeshDef& def,
                        const std::string& json_path) {
  const std::string file = obj_file.string();
  const std::string path = json_path + ".file";
  auto fail = [&](const std::string& problem) -> SceneError { return SceneError(file, path, problem); };

  // Read the whole file (the error says why it cannot be).
  std::error_code ec;
  const fs::file_status status = fs::status(obj_file, ec);
  if (ec || !fs::exists(status)) {
    throw fail(fmt::format("cannot open the OBJ file: {}",
                           ec ? ec.message() : std::string("no such file")));
  }
  if (fs::is_directory(status)) throw fail("cannot open the OBJ file: it is a directory");
  std::string text;
  {
    std::ifstream in(obj_file, std::ios::binary);
    if (!in) throw fail("cannot open the OBJ file (not readable)");
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad()) throw fail("cannot read the OBJ file");
  }

  const ObjScan scan = scan_obj(text, file, path);
  if (scan.face_line.empty()) throw fail("the OBJ file has no faces (\"f\" lines)");

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  NoMaterials no_materials;
  std::istringstream stream(text);
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &stream, &no_materials,
                        /*triangulate=*/false, /*default_vcols_fallback=*/false)) {
    throw fail(fmt::format("malformed OBJ: {}", trim_message(err)));
  }

  ClothMesh mesh;
  mesh.source_bytes = text.size();
  mesh.source_fnv1a64 = fnv1a64(text);

  // Vertices, placed by x_world = x_file * scale + translate.
  const std::size_t vertex_count = attrib.vertices.size() / 3;
  mesh.positions.resize(vertex_count);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    for (int k = 0; k < 3; ++k) {
      const float x = float(attrib.vertices[3 * v + k]) * def.scale + def.translate[k];
      if (!std::isfinite(x)) {
        throw fail(fmt::format("vertex {}: non-finite coordinate after scale and translate", v + 1));
      }
      mesh.positions[v][k] = x;
    }
  }
  const std::size_t texcoord_count = attrib.texcoords.size() / 2;
  mesh.texcoords.resize(texcoord_count);
  for (std::size_t t = 0; t < texcoord_count; ++t) {
    mesh.texcoords[t] = {float(attrib.texcoords[2 * t]), float(attrib.texcoords[2 * t + 1])};
  }

  // Faces as read, in file order (tinyobjloader's shapes come in file order).
  std::size_t face_count = 0;
  for (const tinyobj::shape_t& shape : shapes) face_count += shape.mesh.num_face_vertices.size();
  // "line 7 (face 3)", or "face 3" should tinyobjloader ever count faces differently.
  auto where = [&](std::size_t f) {
    return face_count == scan.face_line.size()
               ? fmt::format("line {} (face {})", scan.face_line[f], f + 1)
               : fmt::format("face {}", f + 1);
  };
  mesh.face_start.reserve(face_count + 1);
  mesh.face_start.push_back(0);
  for (const tinyobj::shape_t& shape : shapes) {
    std::size_t corner = 0;
    for (const unsigned char corners : shape.mesh.num_face_vertices) {
      const std::size_t f = mesh.face_start.size() - 1;
      for (std::size_t k = 0; k < corners; ++k, ++corner) {
        const tinyobj::index_t& index = shape.mesh.indices[corner];
        if (index.vertex_index < 0 || std::size_t(index.vertex_index) >= vertex_count) {
          throw fail(fmt::format("{}: vertex index {} is out of range (the file has {} vertices)",
                                 where(f), std::int64_t(index.vertex_index) + 1, vertex_count));
        }
        std::int32_t texcoord = -1;
        if (index.texcoord_index != -1) {  // -1: the corner has no "vt" index
          if (index.texcoord_index < 0 || std::size_t(index.texcoord_index) >= texcoord_count) {
            throw fail(fmt::format("{}: texture coordinate index {} is out of range (the file has "
                                   "{} \"vt\")",
                                   where(f), std::int64_t(index.texcoord_index) + 1, texcoord_count));
          }
          texcoord = index.texcoord_index;
        }
        mesh.corner_vertex.push_back(std::uint32_t(index.vertex_index));
        mesh.corner_texcoord.push_back(texcoord);
      }
      mesh.face_start.push_back(std::uint32_t(mesh.corner_vertex.size()));
    }
  }
  if (face_count == 0) throw fail("the OBJ file has no faces (\"f\" lines)");

  // Mean squared edge length over the faces' boundary edges: the scale of "degenerate".
  double edge_sum = 0.0;
  std::size_t edge_count = 0;
  for (std::size_t f = 0; f < face_count; ++f) {
    const std::uint32_t begin = mesh.face_start[f], end = mesh.face_start[f + 1];
    for (std::uint32_t c = begin; c < end; ++c) {
      const std::uint32_t next = c + 1 < end ? c + 1 : begin;
      edge_sum += squared_distance(mesh.positions[mesh.corner_vertex[c]],
                                   mesh.positions[mesh.corner_vertex[next]]);
      ++edge_count;
    }
  }
  const double min_area = 1e-12 * (edge_sum / double(edge_count));

  // Fan each face into triangles (c0, ci, ci+1); skip the degenerate ones.
  std::size_t degenerate = 0;
  std::vector<std::size_t> degenerate_faces;  // 1-based
  for (std::size_t f = 0; f < face_count; ++f) {
    const std::uint32_t begin = mesh.face_start[f], end = mesh.face_start[f + 1];
    bool face_listed = false;
    for (std::uint32_t c = begin + 1; c + 1 < end; ++c) {
      const Tri tri{mesh.corner_vertex[begin], mesh.corner_vertex[c], mesh.corner_vertex[c + 1]};
      const bool repeated = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
      if (repeated || !(triangle_area(mesh.positions[tri[0]], mesh.positions[tri[1]],
                                      mesh.positions[tri[2]]) >= min_area) ||
          min_area == 0.0) {
        ++degenerate;
        if (!face_listed) degenerate_faces.push_back(f + 1);
        face_listed = true;
        continue;
      }
      mesh.triangles.push_back(tri);
    }
  }
  if (mesh.triangles.empty()) {
    throw fail(fmt::format("every face is degenerate (a repeated vertex or zero area): no "
                           "triangle to simulate ({} faces)",
                           face_count));
  }
  if (degenerate > 0) {
    mesh.warnings.push_back(fmt::format("{}: {} degenerate triangle{} skipped (face{} {})", file,
                                        degenerate, degenerate == 1 ? "" : "s",
                                        degenerate_faces.size() == 1 ? "" : "s",
                                        list_numbers(degenerate_faces)));
  }

  // Vertices no face uses stay vertices (the vertex order is the file's), with a warning.
  std::vector<char> used(vertex_count, 0);
  for (std::uint32_t v : mesh.corner_vertex) used[v] = 1;
  std::vector<std::size_t> unused;
  for (std::size_t v = 0; v < vertex_count; ++v) {
    if (!used[v]) unused.push_back(v + 1);
  }
  if (!unused.empty()) {
    mesh.warnings.push_back(fmt::format("{}: {} vert{} not used by any face (vert{} {})", file,
                                        unused.size(), unused.size() == 1 ? "ex is" : "ices are",
                                        unused.size() == 1 ? "ex" : "ices", list_numbers(unused)));
  }
  if (!warn.empty()) mesh.warnings.push_back(fmt::format("{}: tinyobjloader: {}", file, trim_message(warn)));
  return mesh;
}

// ---- build_topology ----------------------------------------------------------------------------

ClothTopology build_topology(const ClothMesh& mesh, const std::string& file,
                             const std::string& json_path) {
  ClothTopology topo;
  const std::size_t nv = mesh.vertex_count();
  const std::size_t nt = mesh.triangles.size();

  // One record per triangle edge: key (min << 32 | max), then the triangle. Sorted, each
  // undirected edge's triangles are adjacent, in triangle order.
  struct EdgeRecord {
    std::uint64_t key;
    std::uint32_t tri;
    bool operator<(const EdgeRecord& o) const { return key != o.key ? key < o.key : tri < o.tri; }
  };
  std::vector<EdgeRecord> records;
  records.reserve(3 * nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const Tri& tri = mesh.triangles[t];
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = tri[e], b = tri[(e + 1) % 3];
      if (a == b) continue;
      const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      records.push_back({key, std::uint32_t(t)});
    }
  }
  std::sort(records.begin(), records.end());

  std::size_t non_manifold = 0, worst_count = 0;
  std::uint64_t first_bad_key = 0;
  for (std::size_t r = 0; r < records.size();) {
    std::size_t s = r;
    while (s < records.size() && records[s].key == records[r].key) ++s;
    const std::uint32_t lo = std::uint32_t(records[r].key >> 32);
    const std::uint32_t hi = std::uint32_t(records[r].key & 0xffffffffu);
    const std::size_t count = s - r;
    topo.edges.push_back({lo, hi});
    if (count > 2) {
      if (non_manifold == 0) {
        first_bad_key = records[r].key;
        worst_count = count;
      }
      ++non_manifold;
    } else if (count == 2) {
      // Hinge: (a, b, c) in the first triangle's winding, d the second triangle's third vertex.
      // If the two triangles are inconsistently oriented (both hold a->b) the hinge is still
      // made this way: the dihedral angle's sign is then relative to the first triangle's normal,
      // which is consistent with a rest angle measured the same way.
      const Tri& t1 = mesh.triangles[records[r].tri];
      const Tri& t2 = mesh.triangles[records[r + 1].tri];
      std::array<std::uint32_t, 4> hinge{};
      for (int e = 0; e < 3; ++e) {
        const std::uint32_t a = t1[e], b = t1[(e + 1) % 3];
        if ((a == lo && b == hi) || (a == hi && b == lo)) hinge = {a, b, t1[(e + 2) % 3], 0};
      }
      for (int k = 0; k < 3; ++k) {
        if (t2[k] != lo && t2[k] != hi) hinge[3] = t2[k];
      }
      topo.hinges.push_back(hinge);
    }
    r = s;
  }
  if (non_manifold > 0) {
    throw SceneError(
        file, json_path,
        fmt::format("non-manifold mesh: the edge between vertices {} and {} (1-based) is shared by "
                    "{} triangles (at most 2 for a cloth); {} such edge{}",
                    (first_bad_key >> 32) + 1, (first_bad_key & 0xffffffffu) + 1, worst_count,
                    non_manifold, non_manifold == 1 ? "" : "s"));
  }

  // A third of each triangle's area to each of its vertices.
  topo.vertex_area.assign(nv, 0.0);
  for (const Tri& tri : mesh.triangles) {
    const double third = triangle_area(mesh.positions[tri[0]], mesh.positions[tri[1]],
                                       mesh.positions[tri[2]]) / 3.0;
    for (std::uint32_t v : tri) topo.vertex_area[v] += third;
  }

  // Adjacency: the other two vertices of each triangle, per vertex, sorted and deduplicated.
  std::vector<std::uint32_t> start(nv + 1, 0);
  for (const Tri& tri : mesh.triangles) {
    for (std::uint32_t v : tri) start[v + 1] += 2;
  }
  for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  std::vector<std::uint32_t> raw(start[nv]);
  for (const Tri& tri : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = tri[k];
      raw[fill[v]++] = tri[(k + 1) % 3];
      raw[fill[v]++] = tri[(k + 2) % 3];
    }
  }
  topo.adjacent_start.assign(nv + 1, 0);
  topo.adjacent.reserve(raw.size() / 2);
  for (std::size_t v = 0; v < nv; ++v) {
    auto begin = raw.begin() + start[v], end = raw.begin() + start[v + 1];
    std::sort(begin, end);
    end = std::unique(begin, end);
    for (auto it = begin; it != end; ++it) {
      if (*it != v) topo.adjacent.push_back(*it);
    }
    topo.adjacent_start[v + 1] = std::uint32_t(topo.adjacent.size());
  }
  return topo;
}

// ---- encode_cloth_obj --------------------------------------------------------------------------

std::string encode_cloth_obj(const ClothMesh& mesh, std::span<const Vec3> positions) {
  const std::size_t nv = mesh.vertex_count();
  if (positions.size() != nv) {
    throw std::invalid_argument(fmt::format("encode_cloth_obj: {} positions for a mesh of {} vertices",
                                            positions.size(), nv));
  }

  // Area-weighted vertex normals: the sum of the (unnormalized) cross products of the simulated
  // triangles, whose length is twice the area.
  std::vector<std::array<double, 3>> normal(nv, {0.0, 0.0, 0.0});
  for (const Tri& tri : mesh.triangles) {
    const Vec3 &a = positions[tri[0]], &b = positions[tri[1]], &c = positions[tri[2]];
    const double ux = double(b[0]) - a[0], uy = double(b[1]) - a[1], uz = double(b[2]) - a[2];
    const double vx = double(c[0]) - a[0], vy = double(c[1]) - a[1], vz = double(c[2]) - a[2];
    const std::array<double, 3> n{uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
    for (std::uint32_t v : tri) {
      for (int k = 0; k < 3; ++k) normal[v][k] += n[k];
    }
  }

  // The text is written with std::to_chars into a string sized for the longest possible
  // output, then cut to length (about 4x faster than formatted output for 65k vertices).
  const std::size_t faces = mesh.face_start.empty() ? 0 : mesh.face_start.size() - 1;
  constexpr std::size_t kFloat = 16, kIndex = 11;  // "-1.23456789e-38 ", "4294967295/"
  std::string out;
  out.resize(64 + nv * 2 * (3 + 3 * kFloat) + mesh.texcoords.size() * (3 + 2 * kFloat) +
             mesh.corner_vertex.size() * (1 + 3 * kIndex) + faces * 2);
  char* o = out.data();
  auto text = [&](std::string_view s) {
    std::memcpy(o, s.data(), s.size());
    o += s.size();
  };
  auto number = [&](auto x) { o = std::to_chars(o, o + kFloat, x).ptr; };
  {
    const std::string header = fmt::format("# seiche cloth: {} vertices, {} faces\n", nv, faces);
    text(header);
  }
  for (const Vec3& p : positions) {
    text("v ");
    number(p[0]);
    *o++ = ' ';
    number(p[1]);
    *o++ = ' ';
    number(p[2]);
    *o++ = '\n';
  }
  for (const auto& n : normal) {
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (length > 1e-30 && std::isfinite(length)) {
      text("vn ");
      number(float(n[0] / length));
      *o++ = ' ';
      number(float(n[1] / length));
      *o++ = ' ';
      number(float(n[2] / length));
      *o++ = '\n';
    } else {
      text("vn 0 1 0\n");
    }
  }
  for (const auto& t : mesh.texcoords) {
    text("vt ");
    number(t[0]);
    *o++ = ' ';
    number(t[1]);
    *o++ = '\n';
  }
  for (std::size_t f = 0; f < faces; ++f) {
    *o++ = 'f';
    for (std::uint32_t c = mesh.face_start[f]; c < mesh.face_start[f + 1]; ++c) {
      const std::uint32_t v = mesh.corner_vertex[c] + 1;
      const std::int32_t t = c < mesh.corner_texcoord.size() ? mesh.corner_texcoord[c] : -1;
      *o++ = ' ';
      number(v);
      *o++ = '/';
      if (t >= 0) number(std::uint32_t(t) + 1);
      *o++ = '/';
      number(v);
    }
    *o++ = '\n';
  }
  out.resize(std::size_t(o - out.data()));
  return out;
}

}  // namespace seiche
