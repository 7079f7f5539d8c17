// Anisotropic fluid surface (Yu & Turk 2013, "Reconstructing surfaces of particle-based fluids
// using anisotropic kernels"): every particle becomes an ellipsoid stretched along the principal
// axes of its neighbourhood, so thin sheets stay flat and edges stay sharp where spheres would
// make blobs.
#pragma once

#include <span>

#include <openvdb/openvdb.h>

namespace seiche::exporting {

/// Narrow-band level set (class GRID_LEVEL_SET, negative inside, background = half_width voxels
/// times the voxel size) of the particles at `positions`, on `transform` (a uniform linear
/// transform whose voxel size is the grid's).
/// `spacing`: the fluid's rest particle spacing. `radius`: the sphere radius an interior particle
/// of an undisturbed lattice gets (the isotropic surface's particle radius), so the two surfaces
/// of a resting block agree. Never returns null; an empty input gives an empty grid.
openvdb::FloatGrid::Ptr anisotropic_level_set(std::span<const openvdb::Vec3f> positions, float spacing,
                                              float radius, const openvdb::math::Transform::Ptr& transform,
                                              float half_width);

}  // namespace seiche::exporting
