// Anisotropic fluid surface (Yu & Turk 2013, "Reconstructing surfaces of particle-based fluids
// using anisotropic kernels"): every particle becomes an ellipsoid stretched along the principal
// axes of its neighbourhood, so thin sheets stay flat and edges stay sharp where spheres would
// make blobs. The math, the parameters and why: anisotropic_surface.cpp.
#pragma once

#include <openvdb/openvdb.h>

#include <span>

namespace seiche::exporting {

/// Narrow-band level set (class GRID_LEVEL_SET, negative inside, background = half_width voxels
/// times the voxel size) of the particles at `positions`, on `transform` (a uniform linear
/// transform whose voxel size is the grid's).
/// `spacing`: the fluid's rest particle spacing (> 0). `radius` (> 0): the sphere radius an
/// interior particle of an undisturbed lattice gets; every ellipsoid keeps that sphere's volume,
/// and with radius = spacing a resting block's surface lies on the block's faces (within 0.2
/// voxel at voxel = spacing / 2). Isolated particles (fewer than 12 neighbours within 2.5
/// spacings) are spheres of `radius`. Non-finite positions are skipped. Deterministic: the same
/// grid, bit for bit, for any TBB thread count. Never returns null; an empty input gives an empty
/// grid. Throws std::invalid_argument on a null or non-linear transform, spacing or radius <= 0,
/// or half_width < 1.
openvdb::FloatGrid::Ptr anisotropic_level_set(std::span<const openvdb::Vec3f> positions,
                                              float spacing, float radius,
                                              const openvdb::math::Transform::Ptr& transform,
                                              float half_width);

}  // namespace seiche::exporting
