// A signed distance field on a dense regular grid (negative inside), sampled trilinearly: what
// a triangle-mesh collider becomes (core/src/families/collider/mesh_sdf.hpp builds it from an OBJ).
#pragma once

#include <cstddef>
#include <cstdint>

namespace seiche::kernels {

struct SdfGrid {
  float origin[3] = {0, 0, 0};  ///< world position of sample (0, 0, 0) (m)
  float voxel = 1.0f;           ///< sample spacing (m)
  std::int32_t dims[3] = {0, 0, 0};
  const float* values = nullptr;  ///< dims[0] * dims[1] * dims[2], x fastest (m)

  /// Trilinear distance and its gradient (normalized; (0, 1, 0) where it vanishes) at a point.
  /// Returns false for points outside the sampled box: there the field knows nothing and no
  /// contact is made.
  bool sample(float x, float y, float z, float& distance, float normal[3]) const;
};

}  // namespace seiche::kernels
