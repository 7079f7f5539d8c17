// A mesh body's mass properties and body frame (the integrals and the rules are in body_mesh.hpp).
#include "body_mesh.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "families/closed_mesh.hpp"
#include "families/cloth/cloth_mesh.hpp"
#include "seiche/scene_loader.hpp"

namespace seiche::rigid {

namespace {

// Below this part of the bounding box's diagonal cubed a mesh has no volume.
constexpr double kMinRelativeVolume = 1e-9;
// Products of inertia below this part of the trace are rounding: the tensor is diagonal.
constexpr double kDiagonalTolerance = 1e-12;

// The principal moments and the body-to-mesh rotation of a symmetric tensor (body_mesh.hpp).
void principal_axes(const std::array<std::array<double, 3>, 3>& tensor, Vec3d& moments, Quatd& rotation) {
  const double trace = tensor[0][0] + tensor[1][1] + tensor[2][2];
  const double off = std::fabs(tensor[0][1]) + std::fabs(tensor[0][2]) + std::fabs(tensor[1][2]);
  if (off <= kDiagonalTolerance * std::fabs(trace)) {
    moments = {tensor[0][0], tensor[1][1], tensor[2][2]};
    rotation = {};
    return;
  }
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = tensor[std::size_t(i)][std::size_t(j)];
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(m);
  const Eigen::Matrix3d vectors = solver.eigenvectors();
  const Eigen::Vector3d values = solver.eigenvalues();
  // The assignment of eigenvectors to the body's x, y, z closest to the mesh's own axes.
  std::array<int, 3> best{0, 1, 2}, order{0, 1, 2};
  double best_score = -1.0;
  do {
    const double score =
        std::fabs(vectors(0, order[0])) + std::fabs(vectors(1, order[1])) + std::fabs(vectors(2, order[2]));
    if (score > best_score) best_score = score, best = order;
  } while (std::next_permutation(order.begin(), order.end()));
  Eigen::Matrix3d r;
  for (int a = 0; a < 2; ++a) {
    const Eigen::Vector3d column = vectors.col(best[std::size_t(a)]);
    r.col(a) = column(a) < 0.0 ? Eigen::Vector3d(-column) : column;
  }
  r.col(2) = r.col(0).cross(r.col(1));  // a proper rotation
  moments = {values(best[0]), values(best[1]), values(best[2])};
  const Eigen::Quaterniond q(r);
  rotation = normalized({q.w(), q.x(), q.y(), q.z()});
}

}  // namespace

MeshIntegrals mesh_integrals(std::span<const Vec3d> vertices, std::span<const std::array<std::uint32_t, 3>> triangles) {
  MeshIntegrals out;
  if (vertices.empty()) return out;
  Vec3d lo = vertices[0], hi = vertices[0];
  for (const Vec3d& p : vertices) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const Vec3d reference = 0.5 * (lo + hi);
  double volume = 0.0;
  Vec3d first;
  double second[3][3] = {};
  for (const auto& t : triangles) {
    const Vec3d a = vertices[t[0]] - reference, b = vertices[t[1]] - reference, c = vertices[t[2]] - reference;
    const double v = dot(a, cross(b, c)) / 6.0;
    const Vec3d s = a + b + c;
    volume += v;
    first += (v / 4.0) * s;
    const double pa[3] = {a.x, a.y, a.z}, pb[3] = {b.x, b.y, b.z}, pc[3] = {c.x, c.y, c.z}, ps[3] = {s.x, s.y, s.z};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        second[i][j] += v / 20.0 * (pa[i] * pa[j] + pb[i] * pb[j] + pc[i] * pc[j] + ps[i] * ps[j]);
  }
  out.volume = volume;
  const Vec3d centre = volume != 0.0 ? (1.0 / volume) * first : Vec3d{};
  out.centre = reference + centre;
  const double c[3] = {centre.x, centre.y, centre.z};
  double about_centre[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) about_centre[i][j] = second[i][j] - volume * c[i] * c[j];
  const double trace = about_centre[0][0] + about_centre[1][1] + about_centre[2][2];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      out.inertia[std::size_t(i)][std::size_t(j)] = (i == j ? trace : 0.0) - about_centre[i][j];
  return out;
}

BodyMesh make_body_mesh(const ClothMesh& mesh, double scale, const std::string& file, const std::string& mesh_path) {
  const std::string json_path = mesh_path + ".file";
  const ClosedTriangles closed = closed_triangles(mesh, file, json_path);
  if (!closed.consistent)
    throw SceneError(file, json_path,
                     "the mesh's triangles are not wound consistently (an edge is used twice in the same "
                     "direction), so it has no inside to weigh; wind every face the same way round");
  std::vector<Vec3d> vertices;
  vertices.reserve(mesh.vertex_count());
  for (const Vec3& p : mesh.positions) vertices.push_back(scale * Vec3d{double(p[0]), double(p[1]), double(p[2])});
  const MeshIntegrals integrals = mesh_integrals(vertices, closed.triangles);
  Vec3d lo = vertices[0], hi = vertices[0];
  for (const Vec3d& p : vertices) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const double diagonal = length(hi - lo);
  if (!(std::fabs(integrals.volume) > kMinRelativeVolume * diagonal * diagonal * diagonal))
    throw SceneError(file, json_path,
                     fmt::format("the mesh encloses no volume ({:.3g} m³ in a box {:.3g} m across): a rigid body "
                                 "needs a solid",
                                 integrals.volume, diagonal));
  if (integrals.volume < 0.0)
    throw SceneError(file, json_path,
                     fmt::format("the mesh is wound inward: its volume comes out negative ({:.3g} m³); reverse the "
                                 "vertex order of every face so that the faces' normals point out",
                                 integrals.volume));
  BodyMesh body;
  body.volume = integrals.volume;
  body.centre = integrals.centre;
  principal_axes(integrals.inertia, body.unit_inertia, body.principal);
  if (!(body.unit_inertia.x > 0.0 && body.unit_inertia.y > 0.0 && body.unit_inertia.z > 0.0))
    throw SceneError(file, json_path, "the mesh's inertia tensor is not positive: the solid is degenerate");
  body.triangles = closed.triangles;
  body.vertices.reserve(vertices.size());
  for (const Vec3d& p : vertices) {
    body.vertices.push_back(rotate_back(body.principal, p - body.centre));
    body.extent = std::max(body.extent, length(p - body.centre));
  }
  body.source_bytes = mesh.source_bytes, body.source_fnv1a64 = mesh.source_fnv1a64;
  return body;
}

BodyMesh read_body_mesh(const ClothMeshDef& def, const std::string& mesh_path) {
  const ClothMeshDef as_in_file{def.file, {0.0f, 0.0f, 0.0f}, 1.0f};
  return make_body_mesh(read_obj_mesh(def.file, as_in_file, mesh_path), double(def.scale), def.file, mesh_path);
}

}  // namespace seiche::rigid
