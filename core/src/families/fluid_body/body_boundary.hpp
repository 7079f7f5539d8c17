// A rigid body's boundary particles for the fluid (Akinci et al. 2012, "Versatile Rigid-Fluid
// Coupling for Incompressible SPH"): sites fixed in the body frame that the fluid's density
// constraint sees as fluid of mass rho0 psi_b, so that a fluid particle next to a body reads the
// density it would read next to more fluid.
//
// Sites: the cell centres of a lattice of the fluid's spacing s inside the body's solid (a box's
// lattice fitted to its edges, n_a = max(1, round(size_a / s)) cells per axis; the others' a
// lattice of spacing s centred on the body's origin), those within the kernel radius h of the
// surface (deeper ones are out of every outside fluid particle's reach). A body smaller than a
// cell gets its centre as its one site.
// Volume of site b, over the sites k of its own body (b itself included):
//   psi_b = rho0 / sum_k rho0 W(|x_b - x_k|) = 1 / sum_k W(|x_b - x_k|)
// (poly6 W of support h). Deep in a lattice of spacing s it is the fluid particle's rest volume;
// nearer the surface, where fewer sites surround it, it is larger.
// The sites are sorted into a uniform grid of cell h in the body frame (counting sort in site
// order), so that a query visits the 27 cells around it.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "families/rigid/body_shape.hpp"
#include "families/rigid/rigid_math.hpp"
#include "families/rigid/world_surfaces.hpp"
#include "seiche/scene.hpp"

namespace seiche::fluid_body {

using rigid::Vec3d;

struct BodyBoundary {
  std::vector<Vec3d> sites;   ///< body frame (m), sorted by grid cell
  std::vector<double> psi;    ///< m^3, per site
  double reach = 0.0;         ///< max |site| + h: no fluid particle farther from the centre sees a site
  double extent = 0.0;        ///< the solid's farthest point from the centre (m)
  rigid::SolidSurface solid;  ///< the body's solid in its frame (body_solid.hpp)
  std::shared_ptr<const MeshSdf> field;  ///< a mesh body's field (the solid points into it)

  // The grid: cell (i, j, k) covers lo + [i, i+1) h ...; its sites are [cell_start[c], cell_start[c+1]).
  double h = 0.0;
  Vec3d lo;
  int dims[3] = {0, 0, 0};
  std::vector<std::uint32_t> cell_start;

  /// Calls visit(site index) for every site in the 27 cells around body-frame point q.
  template <class Visit>
  void for_each_site_near(Vec3d q, Visit&& visit) const {
    const double c[3] = {(q.x - lo.x) / h, (q.y - lo.y) / h, (q.z - lo.z) / h};
    int from[3], to[3];
    for (int a = 0; a < 3; ++a) {
      if (!(c[a] > -1.0 && c[a] < double(dims[a]) + 1.0)) return;  // NaN-safe: outside, no site
      const int cell = int(std::floor(c[a]));
      from[a] = cell - 1 < 0 ? 0 : cell - 1;
      to[a] = cell + 1 >= dims[a] ? dims[a] - 1 : cell + 1;
    }
    for (int k = from[2]; k <= to[2]; ++k)
      for (int j = from[1]; j <= to[1]; ++j)
        for (int i = from[0]; i <= to[0]; ++i) {
          const std::size_t cell = (std::size_t(k) * std::size_t(dims[1]) + std::size_t(j)) * std::size_t(dims[0]) +
                                   std::size_t(i);
          for (std::uint32_t s = cell_start[cell]; s < cell_start[cell + 1]; ++s) visit(s);
        }
  }
};

/// The lattice a body is sampled on before its sites are kept (its bounding box at the spacing),
/// and its bound: a body too large for the fluid's spacing is refused when the scene is loaded
/// (the shapes' lattice bound, shape_reader.cpp), not sampled for minutes.
double boundary_lattice_size(const rigid::ShapeDims& dims, double extent, double spacing);
inline constexpr double kMaxBoundaryLattice = 4.0e6 * 4.0;

/// At most how many sites sample_body_boundary keeps for a body of shape `dims` (the memory
/// estimate's count, from the definition alone): a box's exactly (its lattice less the cells
/// whose centres lie deeper than h from every face); a sphere's or a capsule's the lattice cells
/// that fit in its shell of depth h grown by a cell's half-diagonal d on both sides,
/// V_shell(r + d) - V_shell(r - h - d) over s^3 (a kept site's cell lies in that shell), at most
/// the lattice; a mesh's its lattice. At least 1 (a body smaller than a cell has its centre).
double boundary_site_bound(const rigid::ShapeDims& dims, double extent, double spacing, double h);
/// At most how many cells the grid of such a body's sites has: floor(w_a / h) + 1 per axis, w_a
/// the solid's width along it (a box's edge, a sphere's 2r, a capsule's 2r or 2r + length, a
/// mesh's 2 extent), which the sites' box does not exceed.
double boundary_grid_cell_bound(const rigid::ShapeDims& dims, double extent, double h);

/// The boundary of body `def` for a fluid of spacing `spacing` and kernel radius `h` (m); `field`
/// is a mesh body's field (rigid::BodyMeshFields), null for the other shapes.
BodyBoundary sample_body_boundary(const RigidBodyDef& def, std::shared_ptr<const MeshSdf> field, double spacing,
                                  double h);

}  // namespace seiche::fluid_body
