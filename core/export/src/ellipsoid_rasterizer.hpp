// Narrow-band signed distance of a union of ellipsoids (OpenVDB 10 has no ellipsoid rasterizer;
// PointRasterizeEllipsoidsSDF came with OpenVDB 11).
#pragma once

#include <openvdb/openvdb.h>

#include <span>

namespace seiche::exporting {

/// The solid {x : |G (x - center)| <= 1}, G = sum_k u_k u_k^T / a_k, with orthonormal axes u_k
/// and semi-axes a_k > 0 (world units).
struct Ellipsoid {
  openvdb::Vec3f center;
  openvdb::Vec3f axes[3];    ///< unit, mutually orthogonal
  openvdb::Vec3f semi_axes;  ///< m, > 0
};

/// Level set (GRID_LEVEL_SET, negative inside, background = half_width * voxel size, half_width
/// >= 1) of the union of `ellipsoids` on `transform` (any linear transform with uniform voxels).
/// The zero crossing is the ellipsoids' own (exact along their axes, first-order elsewhere); the
/// band holds distances to it rebuilt from the voxels next to it (see the .cpp). Bit-identical
/// for every thread count. Never null; no ellipsoids give an empty grid.
openvdb::FloatGrid::Ptr rasterize_ellipsoids(std::span<const Ellipsoid> ellipsoids,
                                             const openvdb::math::Transform::Ptr& transform,
                                             float half_width);

}  // namespace seiche::exporting
