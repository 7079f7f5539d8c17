// Trilinear sampling of a grid signed distance field (sdf_grid.hpp). With the point at cell
// coordinates (i + fx, j + fy, k + fz), f in [0, 1]:
//   phi = sum over the 8 corners of phi_corner * (fx or 1 - fx)(fy or 1 - fy)(fz or 1 - fz)
// and its gradient is the analytic gradient of that interpolant (per axis: the difference of
// the two faces, interpolated bilinearly in the other two axes, divided by the voxel size),
// normalized; (0, 1, 0) where it vanishes.
#include "seiche/kernels/sdf_grid.hpp"

#include <algorithm>
#include <cmath>

namespace seiche::kernels {

bool SdfGrid::sample(float x, float y, float z, float& distance, float normal[3]) const {
  if (values == nullptr || dims[0] < 2 || dims[1] < 2 || dims[2] < 2 || !(voxel > 0.0f))
    return false;
  const float p[3] = {x, y, z};
  std::int32_t cell[3];
  float f[3];
  for (int axis = 0; axis < 3; ++axis) {
    const float u = (p[axis] - origin[axis]) / voxel;
    if (!(u >= 0.0f && u <= float(dims[axis] - 1))) return false;  // outside (or NaN)
    cell[axis] = std::min(std::int32_t(u), dims[axis] - 2);  // u = dims - 1 uses the last cell
    f[axis] = u - float(cell[axis]);
  }
  const std::size_t sx = 1, sy = std::size_t(dims[0]),
                    sz = std::size_t(dims[0]) * std::size_t(dims[1]);
  const float* v = values + cell[0] * sx + cell[1] * sy + cell[2] * sz;
  // Corners v[ijk] with i, j, k in {0, 1} along x, y, z.
  const float v000 = v[0], v100 = v[sx], v010 = v[sy], v110 = v[sx + sy];
  const float v001 = v[sz], v101 = v[sx + sz], v011 = v[sy + sz], v111 = v[sx + sy + sz];
  const float fx = f[0], fy = f[1], fz = f[2], gx = 1.0f - fx, gy = 1.0f - fy, gz = 1.0f - fz;

  // Interpolate along x on the four x-edges, then along y, then z.
  const float e00 = gx * v000 + fx * v100, e10 = gx * v010 + fx * v110;
  const float e01 = gx * v001 + fx * v101, e11 = gx * v011 + fx * v111;
  const float f0 = gy * e00 + fy * e10, f1 = gy * e01 + fy * e11;
  distance = gz * f0 + fz * f1;

  // d/dfx: x-differences interpolated in y and z; likewise for y and z.
  const float dx = gz * (gy * (v100 - v000) + fy * (v110 - v010)) +
                   fz * (gy * (v101 - v001) + fy * (v111 - v011));
  const float dy = gz * (e10 - e00) + fz * (e11 - e01);
  const float dz = f1 - f0;
  const float len = std::sqrt(dx * dx + dy * dy + dz * dz);  // the 1/voxel factor cancels
  if (len > 1e-20f) {
    normal[0] = dx / len, normal[1] = dy / len, normal[2] = dz / len;
  } else {
    normal[0] = 0.0f, normal[1] = 1.0f, normal[2] = 0.0f;
  }
  return true;
}

}  // namespace seiche::kernels
