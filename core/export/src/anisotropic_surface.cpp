// Placeholder: replaced by the Yu & Turk 2013 anisotropic surface.
#include "anisotropic_surface.hpp"

namespace seiche::exporting {

openvdb::FloatGrid::Ptr anisotropic_level_set(std::span<const openvdb::Vec3f>, float, float,
                                              const openvdb::math::Transform::Ptr& transform, float half_width) {
  auto grid = openvdb::FloatGrid::create(half_width * float(transform->voxelSize()[0]));
  grid->setTransform(transform);
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  return grid;
}

}  // namespace seiche::exporting
