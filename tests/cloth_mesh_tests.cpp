// Cloth meshes and mesh colliders (core/src/families/cloth/cloth_mesh.hpp, core/src/families/collider/mesh_sdf.hpp): generated
// sheets and their topology, OBJ reading and its errors, the per-frame OBJ text, and the signed
// distance field of a closed mesh against analytic shapes and brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "families/cloth/cloth_mesh.hpp"
#include "families/collider/mesh_sdf.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/thread_count.hpp"
#include "test_temp_dir.hpp"

namespace seiche {
namespace {

namespace fs = std::filesystem;
using Tri = std::array<std::uint32_t, 3>;

const fs::path kMeshes = fs::path(SEICHE_SCENES_DIR) / "meshes";
const fs::path kData = fs::path(SEICHE_SCENES_DIR).parent_path() / "tests" / "data";

// The SceneError `f` throws, or nullopt (and a test failure) if it throws none.
template <class F>
std::optional<SceneError> error_of(F&& f) {
  try {
    f();
  } catch (const SceneError& e) {
    return e;
  }
  ADD_FAILURE() << "no SceneError thrown";
  return std::nullopt;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Writes `text` to a file in the test process's temporary folder and returns its path.
fs::path temp_obj(const std::string& name, const std::string& text) {
  const fs::path path = testing_support::temp_path("seiche_cloth_mesh_" + name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Normal (unnormalized) of triangle t of `mesh` at positions `p`.
std::array<double, 3> normal_of(const std::vector<Vec3>& p, const Tri& t) {
  const double ux = p[t[1]][0] - p[t[0]][0], uy = p[t[1]][1] - p[t[0]][1], uz = p[t[1]][2] - p[t[0]][2];
  const double vx = p[t[2]][0] - p[t[0]][0], vy = p[t[2]][1] - p[t[0]][1], vz = p[t[2]][2] - p[t[0]][2];
  return {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
}

// True if `t` is a cyclic rotation of (a, b, c).
bool same_winding(const Tri& t, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  for (int r = 0; r < 3; ++r) {
    if (t[r] == a && t[(r + 1) % 3] == b && t[(r + 2) % 3] == c) return true;
  }
  return false;
}

// ---- sheets ------------------------------------------------------------------------------------

SheetDef sheet(int r0, int r1, std::string plane = "xz", std::array<float, 2> size = {2.0f, 1.5f},
               Vec3 origin = {1.0f, 2.0f, 3.0f}) {
  SheetDef s;
  s.origin = origin;
  s.size = size;
  s.resolution = {r0, r1};
  s.plane = std::move(plane);
  return s;
}

TEST(ClothSheet, VerticesCornersAndTexcoords) {
  const ClothMesh m = make_sheet(sheet(4, 3), "scene.json", "cloths[0].sheet");
  ASSERT_EQ(m.vertex_count(), 12u);
  // Vertex (i, j) = j * 4 + i; plane "xz": first axis x takes size[0], second axis z size[1].
  EXPECT_EQ(m.positions[0], (Vec3{1.0f, 2.0f, 3.0f}));
  EXPECT_EQ(m.positions[3], (Vec3{3.0f, 2.0f, 3.0f}));
  EXPECT_EQ(m.positions[8], (Vec3{1.0f, 2.0f, 4.5f}));
  EXPECT_EQ(m.positions[11], (Vec3{3.0f, 2.0f, 4.5f}));
  EXPECT_FLOAT_EQ(m.positions[1 * 4 + 2][0], 1.0f + 2.0f * 2.0f / 3.0f);
  EXPECT_FLOAT_EQ(m.positions[1 * 4 + 2][2], 3.75f);
  ASSERT_EQ(m.texcoords.size(), 12u);
  EXPECT_FLOAT_EQ(m.texcoords[1 * 4 + 2][0], 2.0f / 3.0f);
  EXPECT_FLOAT_EQ(m.texcoords[1 * 4 + 2][1], 0.5f);
  EXPECT_EQ(m.texcoords[11], (std::array<float, 2>{1.0f, 1.0f}));
  // Output faces are the triangles, each corner using its vertex's texcoord.
  ASSERT_EQ(m.triangles.size(), 2u * 3u * 2u);
  ASSERT_EQ(m.face_start.size(), m.triangles.size() + 1);
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    ASSERT_EQ(m.face_start[f], 3 * f);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(m.corner_vertex[3 * f + k], m.triangles[f][k]);
      EXPECT_EQ(m.corner_texcoord[3 * f + k], std::int32_t(m.triangles[f][k]));
    }
  }
  EXPECT_TRUE(m.warnings.empty());

  // Plane "xy": an upright sheet.
  const ClothMesh up = make_sheet(sheet(2, 2, "xy"), "scene.json", "cloths[0].sheet");
  EXPECT_EQ(up.positions[3], (Vec3{3.0f, 3.5f, 3.0f}));
}

TEST(ClothSheet, NormalsPointAlongThePositiveThirdAxis) {
  const std::map<std::string, int> third{{"xz", 1}, {"zx", 1}, {"xy", 2}, {"yx", 2}, {"yz", 0}, {"zy", 0}};
  for (const auto& [plane, axis] : third) {
    const ClothMesh m = make_sheet(sheet(5, 4, plane), "scene.json", "s");
    for (const Tri& t : m.triangles) {
      const auto n = normal_of(m.positions, t);
      ASSERT_GT(n[axis], 0.0) << plane;
      ASSERT_EQ(n[(axis + 1) % 3], 0.0) << plane;
      ASSERT_EQ(n[(axis + 2) % 3], 0.0) << plane;
    }
  }
}

TEST(ClothSheet, EdgeHingeAndAreaCounts) {
  for (const auto& [r0, r1] : std::vector<std::pair<int, int>>{{2, 2}, {3, 3}, {5, 4}, {7, 2}, {16, 9}}) {
    const SheetDef def = sheet(r0, r1, "xz", {2.0f, 1.5f});
    const ClothMesh m = make_sheet(def, "scene.json", "cloths[0].sheet");
    const ClothTopology topo = build_topology(m, "scene.json", "cloths[0]");
    const std::size_t edges = std::size_t((r0 - 1) * r1 + r0 * (r1 - 1) + (r0 - 1) * (r1 - 1));
    const std::size_t boundary = std::size_t(2 * (r0 - 1) + 2 * (r1 - 1));
    EXPECT_EQ(m.triangles.size(), std::size_t(2 * (r0 - 1) * (r1 - 1)));
    EXPECT_EQ(topo.edges.size(), edges) << r0 << "x" << r1;
    EXPECT_EQ(topo.hinges.size(), edges - boundary) << r0 << "x" << r1;
    double area = 0.0;
    for (double a : topo.vertex_area) area += a;
    EXPECT_NEAR(area, 2.0 * 1.5, 1e-6);
    // Interior vertices: with alternating diagonals, vertex (i, j) with i + j even is in 8
    // triangles (4/3 of a cell's area), with i + j odd in 4 (2/3 of a cell).
    if (r0 >= 4 && r1 >= 3) {
      const double cell = 2.0 / (r0 - 1) * 1.5 / (r1 - 1);
      EXPECT_NEAR(topo.vertex_area[std::size_t(r0 + 1)], cell * 4.0 / 3.0, 1e-6);
      EXPECT_NEAR(topo.vertex_area[std::size_t(r0 + 2)], cell * 2.0 / 3.0, 1e-6);
    }
    EXPECT_TRUE(std::is_sorted(topo.edges.begin(), topo.edges.end()));
    for (const auto& e : topo.edges) EXPECT_LT(e[0], e[1]);
  }
}

// The diagonal of cell (i, j) joins (i, j)-(i+1, j+1) when i + j is even, else (i+1, j)-(i, j+1).
TEST(ClothSheet, DiagonalsAlternateAndAdjacencyIsTheGridNeighborhood) {
  const int r0 = 5, r1 = 4;
  const ClothMesh m = make_sheet(sheet(r0, r1), "scene.json", "s");
  const ClothTopology topo = build_topology(m, "scene.json", "s");
  const std::set<std::array<std::uint32_t, 2>> edges(topo.edges.begin(), topo.edges.end());
  auto id = [&](int i, int j) { return std::uint32_t(j * r0 + i); };
  auto edge = [](std::uint32_t a, std::uint32_t b) {
    return std::array<std::uint32_t, 2>{std::min(a, b), std::max(a, b)};
  };
  for (int j = 0; j + 1 < r1; ++j) {
    for (int i = 0; i + 1 < r0; ++i) {
      const bool even = (i + j) % 2 == 0;
      EXPECT_EQ(edges.count(edge(id(i, j), id(i + 1, j + 1))), even ? 1u : 0u) << i << "," << j;
      EXPECT_EQ(edges.count(edge(id(i + 1, j), id(i, j + 1))), even ? 0u : 1u) << i << "," << j;
    }
  }
  // Expected adjacency of (i, j): its 4 grid neighbours, plus the far corner of each cell around
  // it whose diagonal passes through it.
  ASSERT_EQ(topo.adjacent_start.size(), m.vertex_count() + 1);
  for (int j = 0; j < r1; ++j) {
    for (int i = 0; i < r0; ++i) {
      std::set<std::uint32_t> expected;
      for (auto [di, dj] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        if (i + di >= 0 && i + di < r0 && j + dj >= 0 && j + dj < r1) expected.insert(id(i + di, j + dj));
      }
      for (int cj = j - 1; cj <= j; ++cj) {
        for (int ci = i - 1; ci <= i; ++ci) {
          if (ci < 0 || cj < 0 || ci + 1 >= r0 || cj + 1 >= r1) continue;
          const bool even = (ci + cj) % 2 == 0;
          // The cell's corner opposite to (i, j).
          const int oi = ci == i ? i + 1 : i - 1, oj = cj == j ? j + 1 : j - 1;
          const bool on_main = (ci == i) == (cj == j);  // (i, j) is v00 or v11 of the cell
          if (even == on_main) expected.insert(id(oi, oj));
        }
      }
      const std::uint32_t v = id(i, j);
      const std::vector<std::uint32_t> got(topo.adjacent.begin() + topo.adjacent_start[v],
                                           topo.adjacent.begin() + topo.adjacent_start[v + 1]);
      EXPECT_EQ(got, std::vector<std::uint32_t>(expected.begin(), expected.end())) << i << "," << j;
    }
  }
  // 3 x 3: every diagonal meets the centre.
  const ClothMesh small = make_sheet(sheet(3, 3), "scene.json", "s");
  const ClothTopology t3 = build_topology(small, "scene.json", "s");
  EXPECT_EQ(t3.adjacent_start[5] - t3.adjacent_start[4], 8u);
}

TEST(ClothSheet, HingesJoinTwoTrianglesAcrossTheirEdge) {
  const ClothMesh m = make_sheet(sheet(6, 5), "scene.json", "s");
  const ClothTopology topo = build_topology(m, "scene.json", "s");
  ASSERT_FALSE(topo.hinges.empty());
  std::array<std::uint32_t, 2> previous{0, 0};
  for (const auto& h : topo.hinges) {
    const auto [a, b, c, d] = h;
    EXPECT_NE(c, d);
    // (a, b, c) and (b, a, d) are triangles of the (consistently wound) sheet.
    EXPECT_EQ(std::count_if(m.triangles.begin(), m.triangles.end(),
                            [&](const Tri& t) { return same_winding(t, a, b, c); }), 1);
    EXPECT_EQ(std::count_if(m.triangles.begin(), m.triangles.end(),
                            [&](const Tri& t) { return same_winding(t, b, a, d); }), 1);
    const std::array<std::uint32_t, 2> key{std::min(a, b), std::max(a, b)};
    EXPECT_LT(previous, key);
    previous = key;
  }
}

TEST(ClothSheet, BadDefinitionsNameTheirJsonPath) {
  const std::string base = "cloths[2].sheet";
  for (auto [r0, r1] : {std::pair{1, 4}, {4, 1}, {5000, 2}, {2, 4097}}) {
    const auto e = error_of([&] { make_sheet(sheet(r0, r1), "scene.json", base); });
    ASSERT_TRUE(e);
    EXPECT_EQ(e->file(), "scene.json");
    EXPECT_EQ(e->json_path(), base + ".resolution");
  }
  EXPECT_NO_THROW(make_sheet(sheet(4096, 2), "scene.json", base));
  for (const std::string plane : {"xx", "xw", "x", "xyz", "", "XZ"}) {
    const auto e = error_of([&] { make_sheet(sheet(3, 3, plane), "scene.json", base); });
    ASSERT_TRUE(e) << plane;
    EXPECT_EQ(e->json_path(), base + ".plane") << plane;
  }
  for (const std::array<float, 2> size : {std::array<float, 2>{0.0f, 1.0f}, {1.0f, -2.0f}}) {
    const auto e = error_of([&] { make_sheet(sheet(3, 3, "xz", size), "scene.json", base); });
    ASSERT_TRUE(e);
    EXPECT_EQ(e->json_path(), base + ".size");
  }
}

// ---- OBJ files ---------------------------------------------------------------------------------

ClothMesh read(const fs::path& path, ClothMeshDef def = {}) {
  def.file = path.string();
  return read_obj_mesh(path, def, "cloths[1].mesh");
}

TEST(ClothObj, QuadIsTwoTrianglesAndOneFace) {
  const ClothMesh m = read(kData / "quad.obj");
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.positions[2], (Vec3{1.0f, 1.0f, 0.0f}));
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));  // fanned from corner 0
  EXPECT_EQ(m.triangles[1], (Tri{0, 2, 3}));
  EXPECT_EQ(m.face_start, (std::vector<std::uint32_t>{0, 4}));
  EXPECT_EQ(m.corner_vertex, (std::vector<std::uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(m.corner_texcoord, (std::vector<std::int32_t>{0, 1, 2, 3}));
  ASSERT_EQ(m.texcoords.size(), 4u);
  EXPECT_EQ(m.texcoords[2], (std::array<float, 2>{1.0f, 1.0f}));
  EXPECT_TRUE(m.warnings.empty());
  const ClothTopology topo = build_topology(m, "scene.json", "cloths[1]");
  EXPECT_EQ(topo.edges.size(), 5u);
  ASSERT_EQ(topo.hinges.size(), 1u);
  EXPECT_EQ(topo.hinges[0], (std::array<std::uint32_t, 4>{2, 0, 1, 3}));
  EXPECT_NEAR(topo.vertex_area[0] + topo.vertex_area[1] + topo.vertex_area[2] + topo.vertex_area[3], 1.0, 1e-12);
}

TEST(ClothObj, ScaleAndTranslateAreApplied) {
  ClothMeshDef def;
  def.scale = 2.0f;
  def.translate = {1.0f, -2.0f, 0.5f};
  const ClothMesh m = read(kData / "quad.obj", def);
  EXPECT_EQ(m.positions[0], (Vec3{1.0f, -2.0f, 0.5f}));
  EXPECT_EQ(m.positions[2], (Vec3{3.0f, 0.0f, 0.5f}));
  EXPECT_EQ(m.positions[3], (Vec3{1.0f, 0.0f, 0.5f}));
}

TEST(ClothObj, TheClothDiscAssetIsAManifoldDisc) {
  const ClothMesh m = read(kMeshes / "cloth_disc.obj");
  EXPECT_EQ(m.vertex_count(), 217u);
  EXPECT_EQ(m.triangles.size(), 384u);
  EXPECT_EQ(m.texcoords.size(), 217u);
  EXPECT_TRUE(m.warnings.empty());
  const ClothTopology topo = build_topology(m, "scene.json", "cloths[0]");
  // Euler characteristic of a disc: V - E + F = 1.
  EXPECT_EQ(std::int64_t(m.vertex_count()) - std::int64_t(topo.edges.size()) + std::int64_t(m.triangles.size()), 1);
  double area = 0.0;
  for (double a : topo.vertex_area) area += a;
  EXPECT_NEAR(area, M_PI * 0.25, 0.02);  // a polygon inscribed in the circle
  for (const Tri& t : m.triangles) EXPECT_GT(normal_of(m.positions, t)[1], 0.0);
  for (const Vec3& p : m.positions) {
    EXPECT_EQ(p[1], 0.0f);
    EXPECT_LE(std::hypot(p[0], p[2]), 0.5f + 1e-6f);
  }
}

TEST(ClothObj, MissingFileNamesThePathAndKey) {
  const fs::path path = kData / "no_such_file.obj";
  const auto e = error_of([&] { read(path); });
  ASSERT_TRUE(e);
  EXPECT_EQ(e->file(), path.string());
  EXPECT_EQ(e->json_path(), "cloths[1].mesh.file");
  EXPECT_TRUE(contains(e->problem(), "cannot open")) << e->problem();
  // A folder is not a file either.
  const auto dir = error_of([&] { read(kData); });
  ASSERT_TRUE(dir);
  EXPECT_EQ(dir->json_path(), "cloths[1].mesh.file");
}

TEST(ClothObj, MalformedTextIsRejectedWithItsLine) {
  {
    const auto e = error_of([&] { read(kData / "malformed.obj"); });
    ASSERT_TRUE(e);
    EXPECT_EQ(e->file(), (kData / "malformed.obj").string());
    EXPECT_EQ(e->json_path(), "cloths[1].mesh.file");
    EXPECT_TRUE(contains(e->problem(), "line 3")) << e->problem();
    EXPECT_TRUE(contains(e->problem(), "'abc'")) << e->problem();
  }
  const std::vector<std::pair<std::string, std::string>> cases{
      {"v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 1"},      // too few coordinates
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "line 4"},      // too few corners
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3x\n", "line 4"},   // not an index
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4"},    // indices count from 1
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n", "line 4"},  // bad texcoord index
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", "line 4"},
      {"v 0 0 0\nvt 0.5 x\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 2"},
  };
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const fs::path path = temp_obj("malformed" + std::to_string(c) + ".obj", cases[c].first);
    const auto e = error_of([&] { read(path); });
    ASSERT_TRUE(e) << cases[c].first;
    EXPECT_EQ(e->json_path(), "cloths[1].mesh.file");
    EXPECT_TRUE(contains(e->problem(), cases[c].second)) << cases[c].first << " -> " << e->problem();
  }
}

TEST(ClothObj, IndexOutOfRangeNamesTheFace) {
  const auto e = error_of([&] { read(kData / "index_out_of_range.obj"); });
  ASSERT_TRUE(e);
  EXPECT_EQ(e->json_path(), "cloths[1].mesh.file");
  EXPECT_TRUE(contains(e->problem(), "out of range")) << e->problem();
  EXPECT_TRUE(contains(e->problem(), "face 2")) << e->problem();
  EXPECT_TRUE(contains(e->problem(), "line 7")) << e->problem();
  // A relative index before the first vertex, and a texcoord index past the last "vt".
  for (const std::string text : {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 -2 -1\n",
                                 "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n"}) {
    const auto r = error_of([&] { read(temp_obj("range.obj", text)); });
    ASSERT_TRUE(r) << text;
    EXPECT_TRUE(contains(r->problem(), "out of range")) << r->problem();
  }
  // Relative indices inside the range are fine (and so is a comment after a vertex).
  const ClothMesh m = read(temp_obj("relative.obj", "v 0 0 0 # a comment\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"));
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
}

TEST(ClothObj, NoFacesAndNonFiniteCoordinatesAreErrors) {
  const auto none = error_of([&] { read(kData / "no_faces.obj"); });
  ASSERT_TRUE(none);
  EXPECT_EQ(none->json_path(), "cloths[1].mesh.file");
  EXPECT_TRUE(contains(none->problem(), "no faces")) << none->problem();
  for (const std::string text : {"v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
                                 "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n",
                                 "v 0 0 0\nv 1e300 0 0\nv 0 1 0\nf 1 2 3\n"}) {
    const auto e = error_of([&] { read(temp_obj("nonfinite.obj", text)); });
    ASSERT_TRUE(e) << text;
    EXPECT_TRUE(contains(e->problem(), "non-finite")) << e->problem();
  }
  // Finite in the file, infinite once scaled.
  ClothMeshDef def;
  def.scale = 1e30f;
  const auto scaled = error_of([&] { read(temp_obj("big.obj", "v 0 0 0\nv 1e10 0 0\nv 0 1 0\nf 1 2 3\n"), def); });
  ASSERT_TRUE(scaled);
  EXPECT_TRUE(contains(scaled->problem(), "non-finite")) << scaled->problem();
}

TEST(ClothObj, DegenerateFacesAreSkippedWithAWarning) {
  const ClothMesh m = read(kData / "degenerate.obj");
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Tri{0, 2, 3}));
  EXPECT_EQ(m.face_start.size(), 5u);  // all 4 faces kept for output
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_TRUE(contains(m.warnings[0], "2 degenerate triangles skipped (faces 3, 4)")) << m.warnings[0];
  const ClothTopology topo = build_topology(m, "scene.json", "cloths[1]");
  for (double a : topo.vertex_area) EXPECT_TRUE(std::isfinite(a));
  EXPECT_EQ(topo.vertex_area[4], 0.0);  // vertex 5 is only in the degenerate face
  const std::string obj = encode_cloth_obj(m, m.positions);
  EXPECT_FALSE(contains(obj, "nan"));
  EXPECT_TRUE(contains(obj, "f 1//1 2//2 5//5\n"));  // the degenerate face is still output

  // More than 5 degenerate faces: the first 5 listed, and the count.
  std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  for (int f = 0; f < 7; ++f) text += "f 1 1 2\n";
  text += "f 1 2 3\n";
  const ClothMesh many = read(temp_obj("many.obj", text));
  ASSERT_EQ(many.warnings.size(), 1u);
  EXPECT_TRUE(contains(many.warnings[0], "7 degenerate triangles skipped (faces 1, 2, 3, 4, 5, ...)"))
      << many.warnings[0];

  // Nothing but degenerate faces is an error.
  const auto e = error_of([&] { read(temp_obj("alldegenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")); });
  ASSERT_TRUE(e);
  EXPECT_TRUE(contains(e->problem(), "degenerate")) << e->problem();
}

TEST(ClothObj, UnusedVerticesAreKeptWithAWarning) {
  const ClothMesh m = read(kData / "unused_vertex.obj");
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.positions[2], (Vec3{5.0f, 5.0f, 5.0f}));
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_TRUE(contains(m.warnings[0], "1 vertex is not used by any face (vertex 3)")) << m.warnings[0];
}

TEST(ClothObj, NonManifoldEdgeIsAnError) {
  const ClothMesh m = read(kData / "nonmanifold.obj");
  ASSERT_EQ(m.triangles.size(), 3u);
  const auto e = error_of([&] { build_topology(m, "scene.json", "cloths[1]"); });
  ASSERT_TRUE(e);
  EXPECT_EQ(e->file(), "scene.json");
  EXPECT_EQ(e->json_path(), "cloths[1]");
  EXPECT_TRUE(contains(e->problem(), "vertices 1 and 2 (1-based)")) << e->problem();
  EXPECT_TRUE(contains(e->problem(), "3 triangles")) << e->problem();
}

TEST(ClothObj, InconsistentlyWoundNeighboursStillMakeAHinge) {
  // Both triangles hold 1 -> 2 (0-based 0 -> 1).
  const ClothMesh m = read(temp_obj("flip.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nf 1 2 3\nf 1 2 4\n"));
  const ClothTopology topo = build_topology(m, "scene.json", "c");
  ASSERT_EQ(topo.hinges.size(), 1u);
  EXPECT_EQ(topo.hinges[0], (std::array<std::uint32_t, 4>{0, 1, 2, 3}));
}

// ---- per-frame OBJ text ------------------------------------------------------------------------

struct ParsedObj {
  std::vector<Vec3> v, vn;
  std::vector<std::array<float, 2>> vt;
  std::vector<std::vector<std::array<int, 3>>> f;  // per corner: v, vt (0 = none), vn; 1-based
};

float parse_float(const std::string& s) {
  float x = 0.0f;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  EXPECT_TRUE(ec == std::errc() && end == s.data() + s.size()) << s;
  return x;
}

ParsedObj parse_obj(const std::string& text) {
  ParsedObj obj;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string key, a, b, c;
    ls >> key;
    if (key == "v" || key == "vn") {
      ls >> a >> b >> c;
      (key == "v" ? obj.v : obj.vn).push_back({parse_float(a), parse_float(b), parse_float(c)});
    } else if (key == "vt") {
      ls >> a >> b;
      obj.vt.push_back({parse_float(a), parse_float(b)});
    } else if (key == "f") {
      std::vector<std::array<int, 3>> face;
      std::string corner;
      while (ls >> corner) {
        std::array<int, 3> idx{0, 0, 0};
        const auto s1 = corner.find('/'), s2 = corner.find('/', s1 + 1);
        EXPECT_NE(s2, std::string::npos) << corner;
        idx[0] = std::stoi(corner.substr(0, s1));
        if (s2 > s1 + 1) idx[1] = std::stoi(corner.substr(s1 + 1, s2 - s1 - 1));
        idx[2] = std::stoi(corner.substr(s2 + 1));
        face.push_back(idx);
      }
      obj.f.push_back(face);
    } else {
      EXPECT_TRUE(key.empty() || key[0] == '#') << line;
    }
  }
  return obj;
}

void expect_round_trip(const ClothMesh& m, const std::vector<Vec3>& positions) {
  const ParsedObj obj = parse_obj(encode_cloth_obj(m, positions));
  ASSERT_EQ(obj.v.size(), m.vertex_count());
  ASSERT_EQ(obj.vn.size(), m.vertex_count());
  ASSERT_EQ(obj.vt.size(), m.texcoords.size());
  ASSERT_EQ(obj.f.size(), m.face_start.size() - 1);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    ASSERT_EQ(obj.v[i], positions[i]) << i;  // bit-exact float round trip
    const Vec3& n = obj.vn[i];
    ASSERT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0, 1e-6) << i;
  }
  for (std::size_t t = 0; t < m.texcoords.size(); ++t) ASSERT_EQ(obj.vt[t], m.texcoords[t]);
  for (std::size_t f = 0; f < obj.f.size(); ++f) {
    ASSERT_EQ(obj.f[f].size(), m.face_start[f + 1] - m.face_start[f]);
    for (std::size_t k = 0; k < obj.f[f].size(); ++k) {
      const std::size_t c = m.face_start[f] + k;
      EXPECT_EQ(obj.f[f][k][0], int(m.corner_vertex[c]) + 1);
      EXPECT_EQ(obj.f[f][k][1], m.corner_texcoord[c] + 1);
      EXPECT_EQ(obj.f[f][k][2], int(m.corner_vertex[c]) + 1);
    }
  }
}

TEST(ClothObjText, SheetRoundTrips) {
  const ClothMesh m = make_sheet(sheet(7, 5, "xz", {1.0f, 0.7f}, {0.1f, 1.3f, -0.2f}), "s", "s");
  // At rest every normal is +y.
  const ParsedObj flat = parse_obj(encode_cloth_obj(m, m.positions));
  for (const Vec3& n : flat.vn) EXPECT_EQ(n, (Vec3{0.0f, 1.0f, 0.0f}));
  // Deformed positions with awkward values.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(-0.05f, 0.05f);
  std::vector<Vec3> p = m.positions;
  for (Vec3& x : p) {
    for (float& c : x) c += jitter(rng);
  }
  p[3] = {1e-7f, -123456.789f, 3.40282e38f};
  expect_round_trip(m, p);
}

TEST(ClothObjText, ObjWithTexcoordsRoundTrips) {
  const ClothMesh disc = read(kMeshes / "cloth_disc.obj");
  expect_round_trip(disc, disc.positions);
  const ClothMesh quad = read(kData / "quad.obj");
  expect_round_trip(quad, quad.positions);
  EXPECT_TRUE(contains(encode_cloth_obj(quad, quad.positions), "\nf 1/1/1 2/2/2 3/3/3 4/4/4\n"));
  // Without texcoords corners are "v//vn".
  const ClothMesh cube = read(kMeshes / "cube.obj");
  expect_round_trip(cube, cube.positions);
  EXPECT_TRUE(contains(encode_cloth_obj(cube, cube.positions), "\nf 1//1 3//3 4//4 2//2\n"));
}

TEST(ClothObjText, VanishingNormalIsUp) {
  const ClothMesh m = read(kData / "quad.obj");
  const std::vector<Vec3> collapsed(m.vertex_count(), Vec3{0.5f, 0.5f, 0.5f});
  const ParsedObj obj = parse_obj(encode_cloth_obj(m, collapsed));
  ASSERT_EQ(obj.vn.size(), 4u);
  for (const Vec3& n : obj.vn) EXPECT_EQ(n, (Vec3{0.0f, 1.0f, 0.0f}));
  // The quad lies in z = 0 wound counter-clockwise: +z normals.
  const ParsedObj flat = parse_obj(encode_cloth_obj(m, m.positions));
  for (const Vec3& n : flat.vn) EXPECT_EQ(n, (Vec3{0.0f, 0.0f, 1.0f}));
}

// ---- mesh SDF ----------------------------------------------------------------------------------

// Icosphere of radius 1 subdivided `levels` times, wound outward; faces = triangles.
ClothMesh icosphere(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> v{{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                       {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                       {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  auto normalize = [](std::array<double, 3> p) {
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / r, p[1] / r, p[2] / r};
  };
  for (auto& p : v) p = normalize(p);
  std::vector<Tri> f{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                     {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                     {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                     {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(normalize({(v[a][0] + v[b][0]) / 2, (v[a][1] + v[b][1]) / 2, (v[a][2] + v[b][2]) / 2}));
      return mid[key] = std::uint32_t(v.size() - 1);
    };
    std::vector<Tri> next;
    for (const Tri& tri : f) {
      const std::uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]), ca = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = std::move(next);
  }
  ClothMesh m;
  for (const auto& p : v) m.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
  m.triangles = f;
  m.face_start.push_back(0);
  for (const Tri& tri : f) {
    for (std::uint32_t x : tri) {
      m.corner_vertex.push_back(x);
      m.corner_texcoord.push_back(-1);
    }
    m.face_start.push_back(std::uint32_t(m.corner_vertex.size()));
  }
  return m;
}

// Torus around the y axis (radii R, r), nu x nv quads split into triangles, wound outward.
ClothMesh torus(double R, double r, int nu, int nv) {
  ClothMesh m;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, w = 2 * M_PI * j / nv;
      m.positions.push_back({float((R + r * std::cos(w)) * std::cos(u)), float(r * std::sin(w)),
                             float((R + r * std::cos(w)) * std::sin(u))});
    }
  }
  auto id = [&](int i, int j) { return std::uint32_t((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  }
  // Wind outward: the normal of the first triangle must point away from the tube's centre line.
  const Tri& t0 = m.triangles[0];
  const auto n = normal_of(m.positions, t0);
  const Vec3& p = m.positions[t0[0]];
  const double radial = std::hypot(p[0], p[2]);
  const double out[3] = {p[0] - R * p[0] / radial, p[1], p[2] - R * p[2] / radial};
  if (n[0] * out[0] + n[1] * out[1] + n[2] * out[2] < 0) {
    for (Tri& t : m.triangles) std::swap(t[1], t[2]);
  }
  return m;  // no faces: build_mesh_sdf uses the triangles
}

struct GridPoint {
  double x, y, z;
};
GridPoint grid_point(const kernels::SdfGrid& g, int i, int j, int k) {
  return {g.origin[0] + double(i) * g.voxel, g.origin[1] + double(j) * g.voxel,
          g.origin[2] + double(k) * g.voxel};
}

// Trilinear value of the grid at a point inside it (written here so that the test checks the
// samples themselves, not a sampler).
double trilinear(const MeshSdf& sdf, double x, double y, double z) {
  const kernels::SdfGrid& g = sdf.grid;
  const double f[3] = {(x - g.origin[0]) / g.voxel, (y - g.origin[1]) / g.voxel, (z - g.origin[2]) / g.voxel};
  int c[3];
  double w[3];
  for (int a = 0; a < 3; ++a) {
    c[a] = std::clamp(int(std::floor(f[a])), 0, g.dims[a] - 2);
    w[a] = f[a] - c[a];
  }
  double value = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const int d[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
    double weight = 1.0;
    for (int a = 0; a < 3; ++a) weight *= d[a] ? w[a] : 1.0 - w[a];
    const std::size_t s = (std::size_t(c[2] + d[2]) * g.dims[1] + std::size_t(c[1] + d[1])) * g.dims[0] + std::size_t(c[0] + d[0]);
    value += weight * sdf.values[s];
  }
  return value;
}

double value_at(const MeshSdf& sdf, int i, int j, int k) {
  const kernels::SdfGrid& g = sdf.grid;
  return sdf.values[(std::size_t(k) * g.dims[1] + std::size_t(j)) * g.dims[0] + std::size_t(i)];
}

template <class F>
void for_each_sample(const MeshSdf& sdf, F&& f) {
  const kernels::SdfGrid& g = sdf.grid;
  for (int k = 0; k < g.dims[2]; ++k) {
    for (int j = 0; j < g.dims[1]; ++j) {
      for (int i = 0; i < g.dims[0]; ++i) f(grid_point(g, i, j, k), value_at(sdf, i, j, k));
    }
  }
}

double box_distance(const GridPoint& p, double half) {
  const double q[3] = {std::abs(p.x) - half, std::abs(p.y) - half, std::abs(p.z) - half};
  const double outside = std::sqrt(std::pow(std::max(q[0], 0.0), 2) + std::pow(std::max(q[1], 0.0), 2) +
                                   std::pow(std::max(q[2], 0.0), 2));
  return outside + std::min(std::max({q[0], q[1], q[2]}), 0.0);
}

TEST(MeshSdf, CubeIsTheBoxDistanceEverywhere) {
  const ClothMesh cube = read(kMeshes / "cube.obj");
  MeshSdf sdf;
  const float voxel = 1.0f / 32.0f, band = 0.25f;
  build_mesh_sdf(cube, voxel, band, "scene.json", "colliders[0].mesh", sdf);
  const kernels::SdfGrid& g = sdf.grid;
  EXPECT_EQ(g.values, sdf.values.data());
  EXPECT_EQ(g.voxel, voxel);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(g.dims[a], 49);  // (1 + 2 * 0.25) / (1/32) + 1
    EXPECT_LE(g.origin[a], -0.75f + 1e-6f);
    EXPECT_GE(g.origin[a] + (g.dims[a] - 1) * voxel, 0.75f - 1e-6f);
  }
  ASSERT_EQ(sdf.values.size(), std::size_t(49 * 49 * 49));
  double worst = 0.0;
  int wrong_sign = 0;
  for_each_sample(sdf, [&](const GridPoint& p, double d) {
    const double exact = box_distance(p, 0.5);
    worst = std::max(worst, std::abs(d - exact));
    if (std::abs(exact) > 1e-6 && (d < 0) != (exact < 0)) ++wrong_sign;
  });
  EXPECT_LT(worst, 1e-6);
  EXPECT_EQ(wrong_sign, 0);
  EXPECT_NEAR(value_at(sdf, 24, 24, 24), -0.5, 1e-6);  // the centre
}

TEST(MeshSdf, IcosphereIsTheSphereDistanceUpToTheMeshError) {
  const ClothMesh sphere = read(kMeshes / "icosphere.obj");
  ASSERT_EQ(sphere.triangles.size(), 320u);
  // Hausdorff distance between the icosphere and the unit sphere: the deepest face plane.
  double hausdorff = 0.0;
  for (const Tri& t : sphere.triangles) {
    const auto n = normal_of(sphere.positions, t);
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const Vec3& a = sphere.positions[t[0]];
    hausdorff = std::max(hausdorff, 1.0 - (n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / len);
  }
  ASSERT_LT(hausdorff, 0.02);
  MeshSdf sdf;
  const float voxel = 1.0f / 24.0f;
  build_mesh_sdf(sphere, voxel, 0.2f, "scene.json", "colliders[0].mesh", sdf);

  // At the samples: exact distances to the polyhedron, so within the Hausdorff distance.
  double worst = 0.0;
  int wrong_sign = 0;
  for_each_sample(sdf, [&](const GridPoint& p, double d) {
    const double exact = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z) - 1.0;
    worst = std::max(worst, std::abs(d - exact));
    if (std::abs(exact) > hausdorff && (d < 0) != (exact < 0)) ++wrong_sign;
  });
  EXPECT_LT(worst, hausdorff + 1e-5);
  EXPECT_EQ(wrong_sign, 0);

  // Between the samples (trilinear), away from the kink at the centre: within half a voxel.
  const kernels::SdfGrid& g = sdf.grid;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int tested = 0;
  while (tested < 20000) {
    const double x = g.origin[0] + u(rng) * (g.dims[0] - 1) * g.voxel;
    const double y = g.origin[1] + u(rng) * (g.dims[1] - 1) * g.voxel;
    const double z = g.origin[2] + u(rng) * (g.dims[2] - 1) * g.voxel;
    const double r = std::sqrt(x * x + y * y + z * z);
    if (r < 0.4) continue;
    ++tested;
    const double d = trilinear(sdf, x, y, z), exact = r - 1.0;
    ASSERT_LT(std::abs(d - exact), 0.5 * voxel + hausdorff) << x << " " << y << " " << z;
    if (std::abs(exact) > hausdorff + 0.5 * voxel) {
      ASSERT_EQ(d < 0, exact < 0);
    }
  }
}

// Exact squared distance from p to a triangle, by brute force over a fine barycentric search
// seeded with the vertices, edges and plane (independent of the code under test).
double brute_distance(const ClothMesh& m, const GridPoint& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Tri& t : m.triangles) {
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k) {
      a[k] = m.positions[t[0]][k];
      b[k] = m.positions[t[1]][k];
      c[k] = m.positions[t[2]][k];
    }
    const double q[3] = {p.x, p.y, p.z};
    auto seg = [&](const double* s0, const double* s1) {
      double d[3], w[3], dd = 0, dw = 0;
      for (int k = 0; k < 3; ++k) {
        d[k] = s1[k] - s0[k];
        w[k] = q[k] - s0[k];
        dd += d[k] * d[k];
        dw += d[k] * w[k];
      }
      const double s = std::clamp(dw / dd, 0.0, 1.0);
      double r = 0;
      for (int k = 0; k < 3; ++k) r += std::pow(q[k] - (s0[k] + s * d[k]), 2);
      return r;
    };
    double e = std::min({seg(a, b), seg(b, c), seg(c, a)});
    // Projection onto the plane, if it falls inside (barycentric by areas).
    double u[3], v[3], n[3];
    for (int k = 0; k < 3; ++k) {
      u[k] = b[k] - a[k];
      v[k] = c[k] - a[k];
    }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    const double h = (n[0] * (q[0] - a[0]) + n[1] * (q[1] - a[1]) + n[2] * (q[2] - a[2])) / nn;
    double f[3];
    for (int k = 0; k < 3; ++k) f[k] = q[k] - h * n[k];
    auto sub_area = [&](const double* x, const double* y) {
      const double s[3] = {x[0] - f[0], x[1] - f[1], x[2] - f[2]};
      const double r[3] = {y[0] - f[0], y[1] - f[1], y[2] - f[2]};
      return n[0] * (s[1] * r[2] - s[2] * r[1]) + n[1] * (s[2] * r[0] - s[0] * r[2]) + n[2] * (s[0] * r[1] - s[1] * r[0]);
    };
    if (sub_area(a, b) >= 0 && sub_area(b, c) >= 0 && sub_area(c, a) >= 0) e = std::min(e, h * h * nn);
    best = std::min(best, e);
  }
  return std::sqrt(best);
}

TEST(MeshSdf, TorusMatchesBruteForceAndItsHoleIsOutside) {
  const double R = 0.6, r = 0.25;
  const ClothMesh m = torus(R, r, 24, 12);
  MeshSdf sdf;
  const float voxel = 0.05f;
  build_mesh_sdf(m, voxel, 0.15f, "scene.json", "colliders[0].mesh", sdf);
  // Deviation of the mesh from the smooth torus (its vertices lie on it): bounded by the
  // analytic distance of the triangle centroids, with a margin.
  double deviation = 0.0;
  for (const Tri& t : m.triangles) {
    double c[3] = {0, 0, 0};
    for (std::uint32_t v : t) {
      for (int k = 0; k < 3; ++k) c[k] += m.positions[v][k] / 3.0;
    }
    deviation = std::max(deviation, std::abs(std::hypot(std::hypot(c[0], c[2]) - R, c[1]) - r));
  }
  // Within 1.5 voxels of the mesh the distance is exact (up to float rounding); farther away it
  // is the distance to some triangle, so never smaller than the truth, and near it.
  double worst_near = 0.0, worst_far = 0.0, too_small = 0.0;
  int wrong_sign = 0, samples = 0;
  for_each_sample(sdf, [&](const GridPoint& p, double d) {
    ++samples;
    const double exact = brute_distance(m, p), error = std::abs(d) - exact;
    (exact <= 1.5 * voxel ? worst_near : worst_far) = std::max(exact <= 1.5 * voxel ? worst_near : worst_far, std::abs(error));
    too_small = std::max(too_small, -error);
    const double analytic = std::hypot(std::hypot(p.x, p.z) - R, p.y) - r;
    if (std::abs(analytic) > 2.0 * deviation && (d < 0) != (analytic < 0)) ++wrong_sign;
  });
  EXPECT_LT(worst_near, 1e-6) << "over " << samples << " samples";
  EXPECT_LT(worst_far, 0.05 * voxel);
  EXPECT_LT(too_small, 1e-6);
  EXPECT_EQ(wrong_sign, 0);
  // The hole (the y axis) is outside, the tube's core inside.
  const kernels::SdfGrid& g = sdf.grid;
  EXPECT_GT(trilinear(sdf, 0.0, 0.0, 0.0), R - r - 0.05);
  EXPECT_LT(trilinear(sdf, R, 0.0, 0.0), -0.2);
  EXPECT_GT(g.dims[0], 0);
}

// Reversing every face, or only some (an inconsistently wound file), changes nothing.
TEST(MeshSdf, SignDoesNotDependOnWinding) {
  const ClothMesh cube = read(kMeshes / "cube.obj");
  MeshSdf reference;
  build_mesh_sdf(cube, 0.05f, 0.1f, "scene.json", "c", reference);
  auto reversed = [&](auto flip_face) {
    ClothMesh m = read(kMeshes / "cube.obj");
    for (std::size_t f = 0; f + 1 < m.face_start.size(); ++f) {
      if (flip_face(f)) std::reverse(m.corner_vertex.begin() + m.face_start[f], m.corner_vertex.begin() + m.face_start[f + 1]);
    }
    return m;
  };
  for (int mode = 0; mode < 2; ++mode) {
    const ClothMesh m = reversed([&](std::size_t f) { return mode == 0 || f == 2; });
    MeshSdf sdf;
    build_mesh_sdf(m, 0.05f, 0.1f, "scene.json", "c", sdf);
    ASSERT_EQ(sdf.values.size(), reference.values.size());
    // Reversed quads fan along the other diagonal: the same surface, other float rounding.
    for (std::size_t s = 0; s < sdf.values.size(); ++s) {
      ASSERT_NEAR(sdf.values[s], reference.values[s], 1e-6) << mode;
      if (std::abs(reference.values[s]) > 1e-6) {
        ASSERT_EQ(sdf.values[s] < 0, reference.values[s] < 0) << mode;
      }
    }
  }
}

// Two overlapping closed cubes, both wound outward: their overlap is inside (non-zero winding
// number), not outside as an even-odd count would have it.
TEST(MeshSdf, OverlappingShellsAreInside) {
  ClothMesh m = read(kMeshes / "cube.obj");
  const ClothMesh other = read(kMeshes / "cube.obj");
  const auto offset = std::uint32_t(m.vertex_count());
  for (Vec3 p : other.positions) {
    p[0] += 0.5f;
    m.positions.push_back(p);
  }
  for (std::size_t f = 0; f + 1 < other.face_start.size(); ++f) {
    for (std::uint32_t c = other.face_start[f]; c < other.face_start[f + 1]; ++c) {
      m.corner_vertex.push_back(other.corner_vertex[c] + offset);
      m.corner_texcoord.push_back(-1);
    }
    m.face_start.push_back(std::uint32_t(m.corner_vertex.size()));
  }
  for (Tri t : other.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  MeshSdf sdf;
  build_mesh_sdf(m, 0.05f, 0.1f, "scene.json", "c", sdf);
  EXPECT_NEAR(trilinear(sdf, 0.25, 0.35, 0.0), -0.15, 1e-5);  // in both
  EXPECT_NEAR(trilinear(sdf, -0.3, 0.0, 0.0), -0.2, 1e-5);   // in the first only
  EXPECT_NEAR(trilinear(sdf, 0.8, 0.0, 0.0), -0.2, 1e-5);    // in the second only
  EXPECT_NEAR(trilinear(sdf, 1.1, 0.0, 0.0), 0.1, 1e-5);     // outside both
}

TEST(MeshSdf, OpenMeshIsRejected) {
  const ClothMesh open = read(kData / "open_box.obj");
  MeshSdf sdf;
  const auto e = error_of([&] { build_mesh_sdf(open, 0.05f, 0.1f, "scene.json", "colliders[3].mesh", sdf); });
  ASSERT_TRUE(e);
  EXPECT_EQ(e->file(), "scene.json");
  EXPECT_EQ(e->json_path(), "colliders[3].mesh.file");  // a problem of the mesh: its file
  EXPECT_TRUE(contains(e->problem(), "closed")) << e->problem();
  EXPECT_TRUE(contains(e->problem(), "vertices 3 and 4 (1-based) belongs to 1 triangle")) << e->problem();
  EXPECT_TRUE(contains(e->problem(), "4 such edges")) << e->problem();
  // A cloth sheet is open too.
  const ClothMesh sheet_mesh = make_sheet(sheet(3, 3), "s", "s");
  EXPECT_TRUE(error_of([&] { build_mesh_sdf(sheet_mesh, 0.05f, 0.1f, "scene.json", "colliders[3].mesh", sdf); }));
  // A non-positive voxel is an error, not a huge allocation; so is a field of more than 2^26
  // samples. Both are problems of the voxel size, and name it (the size error once named the file).
  const ClothMesh cube = read(kMeshes / "cube.obj");
  for (float voxel : {0.0f, 1e-5f}) {
    const auto v = error_of([&] { build_mesh_sdf(cube, voxel, 0.1f, "scene.json", "colliders[3].mesh", sdf); });
    ASSERT_TRUE(v) << voxel;
    EXPECT_EQ(v->json_path(), "colliders[3].mesh.voxel_size") << v->problem();
  }
  EXPECT_TRUE(contains(error_of([&] { build_mesh_sdf(cube, 1e-5f, 0.1f, "scene.json", "colliders[3].mesh", sdf); })
                           ->problem(),
                       "too small for this mesh"));
}

// The reader drops the zero-area face of this closed tetrahedron; the field still takes the mesh
// as closed and signs it right.
TEST(MeshSdf, ZeroAreaSliverKeepsTheMeshClosed) {
  const ClothMesh m = read(kData / "tetra_sliver.obj");
  EXPECT_EQ(m.triangles.size(), 5u);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_TRUE(contains(m.warnings[0], "(face 3)")) << m.warnings[0];
  MeshSdf sdf;
  const float voxel = 0.05f;
  build_mesh_sdf(m, voxel, 0.1f, "scene.json", "c", sdf);
  int wrong = 0;
  for_each_sample(sdf, [&](const GridPoint& p, double d) {
    // Inside the tetrahedron x, y, z >= 0 and x + y + z <= 1: the distance to its planes.
    const double plane = std::max({-p.x, -p.y, -p.z, (p.x + p.y + p.z - 1.0) / std::sqrt(3.0)});
    if (std::abs(plane) > 1e-6 && (d < 0) != (plane < 0)) ++wrong;
    if (plane < 0 && std::abs(d + std::min({p.x, p.y, p.z, (1.0 - p.x - p.y - p.z) / std::sqrt(3.0)})) > 1e-6) ++wrong;
  });
  EXPECT_EQ(wrong, 0);
}

TEST(MeshSdf, SameBitsWithOneAndTwoThreads) {
  const ClothMesh m = icosphere(4);  // 5120 triangles
  ASSERT_EQ(m.triangles.size(), 5120u);
  MeshSdf one, two;
  run_with_threads(1, [&] { build_mesh_sdf(m, 2.2f / 64.0f, 0.05f, "scene.json", "c", one); });
  run_with_threads(2, [&] { build_mesh_sdf(m, 2.2f / 64.0f, 0.05f, "scene.json", "c", two); });
  ASSERT_EQ(one.values.size(), two.values.size());
  ASSERT_GT(one.values.size(), 200000u);
  EXPECT_EQ(std::memcmp(one.values.data(), two.values.data(), one.values.size() * sizeof(float)), 0);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(one.grid.dims[a], two.grid.dims[a]);
    EXPECT_EQ(one.grid.origin[a], two.grid.origin[a]);
  }
}

}  // namespace
}  // namespace seiche
