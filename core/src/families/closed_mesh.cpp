// The closed triangle set of a mesh and its check (contract in closed_mesh.hpp).
#include "closed_mesh.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "seiche/scene_loader.hpp"

namespace seiche {

ClosedTriangles closed_triangles(const ClothMesh& mesh, const std::string& file, const std::string& json_path) {
  const std::size_t nv = mesh.vertex_count();
  ClosedTriangles out;
  std::vector<std::array<std::uint32_t, 3>>& closed = out.triangles;
  auto add_closed = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    if (a >= nv || b >= nv || c >= nv) {
      throw std::invalid_argument("closed_triangles: a vertex index is out of range");
    }
    if (a != b && b != c && a != c) closed.push_back({a, b, c});
  };
  if (mesh.face_start.size() >= 2) {
    for (std::size_t f = 0; f + 1 < mesh.face_start.size(); ++f) {
      const std::uint32_t begin = mesh.face_start[f], end = mesh.face_start[f + 1];
      for (std::uint32_t c = begin + 1; c + 1 < end; ++c) {
        add_closed(mesh.corner_vertex[begin], mesh.corner_vertex[c], mesh.corner_vertex[c + 1]);
      }
    }
  } else {
    for (const auto& t : mesh.triangles) add_closed(t[0], t[1], t[2]);
  }
  if (closed.empty()) throw SceneError(file, json_path, "the mesh has no triangles");

  std::vector<std::uint64_t> directed;  // (min << 33 | max << 1 | forward)
  directed.reserve(3 * closed.size());
  for (const auto& t : closed) {
    for (int e = 0; e < 3; ++e) {
      const std::uint64_t a = t[e], b = t[(e + 1) % 3];
      directed.push_back((std::min(a, b) << 33) | (std::max(a, b) << 1) | (a < b ? 1u : 0u));
    }
  }
  std::sort(directed.begin(), directed.end());
  std::size_t open = 0, first_count = 0;
  std::uint64_t first_open = 0;
  for (std::size_t r = 0; r < directed.size();) {
    std::size_t s = r;
    while (s < directed.size() && (directed[s] >> 1) == (directed[r] >> 1)) ++s;
    if (s - r != 2) {
      if (open == 0) {
        first_open = directed[r] >> 1;
        first_count = s - r;
      }
      ++open;
    } else if ((directed[r] & 1) == (directed[r + 1] & 1)) {
      out.consistent = false;
    }
    r = s;
  }
  if (open > 0) {
    throw SceneError(file, json_path,
                     fmt::format("the mesh must be closed (every edge shared by exactly "
                                 "two triangles): the edge between vertices {} and {} (1-based) "
                                 "belongs to {} triangle{}; {} such edge{}",
                                 (first_open >> 32) + 1, (first_open & 0xffffffffu) + 1, first_count,
                                 first_count == 1 ? "" : "s", open, open == 1 ? "" : "s"));
  }
  return out;
}

}  // namespace seiche
