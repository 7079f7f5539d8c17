// The fluid particles as a VDB Points grid: positions (16-bit fixed point inside each voxel, so
// an error of at most voxel / 2^17), attribute "v" (velocity, Vec3f; 16-bit half floats when
// asked) and attribute "id" (int32, the particle's creation index). Points are bucketed per voxel
// by OpenVDB and keep the input order inside a voxel.
#pragma once

#include <openvdb/points/PointDataGrid.h>

#include <cstdint>
#include <span>

namespace seiche::exporting {

/// Voxel size of the points grid, in units of the spacing: 8 particles per voxel at rest, as
/// OpenVDB recommends for VDB Points.
inline constexpr float kPointsVoxelPerSpacing = 2.0f;

struct FluidPointArrays {
  std::span<const float> x, y, z;     ///< m
  std::span<const float> vx, vy, vz;  ///< m/s
  std::span<const std::int32_t> id;
};

/// The grid "points"; throws std::invalid_argument when the arrays differ in length.
openvdb::points::PointDataGrid::Ptr fluid_points_grid(const FluidPointArrays& particles,
                                                      float voxel_size, bool half_float_velocity);

}  // namespace seiche::exporting
