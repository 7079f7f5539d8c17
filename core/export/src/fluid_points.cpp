// VDB Points of the fluid particles: see fluid_points.hpp. OpenVDB's PointIndexGrid partitions
// the points per voxel; positions, then "v" and "id" are populated through it, so every
// attribute lands in the same point order.
#include "fluid_points.hpp"

#include <openvdb/points/PointAttribute.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/tools/PointIndexGrid.h>

#include <stdexcept>
#include <vector>

namespace seiche::exporting {

openvdb::points::PointDataGrid::Ptr fluid_points_grid(const FluidPointArrays& p, float voxel_size,
                                                      bool half_float_velocity) {
  namespace points = openvdb::points;
  const std::size_t n = p.x.size();
  if (p.y.size() != n || p.z.size() != n || p.vx.size() != n || p.vy.size() != n ||
      p.vz.size() != n || p.id.size() != n)
    throw std::invalid_argument("fluid points: the particle arrays differ in length");
  if (!(voxel_size > 0.0f)) throw std::invalid_argument("fluid points: voxel size must be > 0");

  std::vector<openvdb::Vec3f> positions(n), velocities(n);
  for (std::size_t i = 0; i < n; ++i) {
    positions[i] = openvdb::Vec3f(p.x[i], p.y[i], p.z[i]);
    velocities[i] = openvdb::Vec3f(p.vx[i], p.vy[i], p.vz[i]);
  }
  const std::vector<std::int32_t> ids(p.id.begin(), p.id.end());

  const auto transform = openvdb::math::Transform::createLinearTransform(double(voxel_size));
  const points::PointAttributeVector<openvdb::Vec3f> position_array(positions);
  const auto index_grid = openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(
      position_array, *transform);
  auto grid =
      points::createPointDataGrid<points::FixedPointCodec</*OneByte=*/false>,
                                  points::PointDataGrid>(*index_grid, position_array, *transform);

  auto& tree = grid->tree();
  if (half_float_velocity)
    points::appendAttribute<openvdb::Vec3f, points::TruncateCodec>(tree, "v");
  else
    points::appendAttribute<openvdb::Vec3f, points::NullCodec>(tree, "v");
  points::populateAttribute(tree, index_grid->tree(), "v",
                            points::PointAttributeVector<openvdb::Vec3f>(velocities));
  points::appendAttribute<std::int32_t>(tree, "id");
  points::populateAttribute(tree, index_grid->tree(), "id",
                            points::PointAttributeVector<std::int32_t>(ids));
  grid->setName("points");
  return grid;
}

}  // namespace seiche::exporting
