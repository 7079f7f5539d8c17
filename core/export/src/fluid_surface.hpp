// The fluid's surface as a narrow-band level set: a raw field gathered per voxel leaf, smoothed,
// then lifted where a particle would be left outside.
//
// Raw field (s = spacing, h = 2 s, dx = voxel size, in the band |phi| < w dx):
//   c(x)  = sum_p W(|x - p|) / C,  W(r) = (1 - r^2/h^2)^3,  C: least sum inside a rest lattice
//   phi_c = h F^-1(c),  F(x) = (G(1) - G(x)) / 2 G(1),  G(t) = integral of (1 - t^2)^4
//   phi_s = min_p |x - p| - s                    (spheres of radius one spacing)
//   phi   = clamp(min(phi_c, phi_s) + e, -w dx, w dx),  e = s/4 (0 without smoothing)
// then two passes of a 3-voxel box filter (LevelSetFilter's mean filter without its
// renormalisation: flat faces do not move, bumps of a voxel or two flatten), then the lift.
//
// Why: this is the scheme "spheres of radius ~ spacing, shrink back, smooth" (a dilation that
// fills the lattice's gaps, an erosion, a low-pass), with the erosion e calibrated so that a
// resting block's faces land on the block (measured: 0.08 s outside on average). phi_c is the
// SPH density's half-rest-density isosurface written as a distance: F(x) is the density a flat
// face gives at signed distance x h from it (a slice of the kernel ball at height t h holds a
// share (1 - t^2)^4 of its mass), so phi_c has unit gradient at the surface and saturates at -h
// deep inside, where the spheres' union alone would read -s at most: it makes the band's inner
// half a distance. The lift: a simulated free surface is rough at the particle scale (the dam
// break at frame 30: particle heights vary by about s/3), and any smooth surface leaves its high
// points out (3 % of the particles there; OpenVDB's ParticlesToLevelSet + offset + 2 mean passes
// leaves 4 %). Each such particle gets the least lift that takes it in: the 8 voxels of its cell
// are lowered by its deficit phi(p) + 0.05 dx, so phi interpolated at p is -0.05 dx; spray more
// than s/2 outside gets a bead, a sphere of radius s/2, instead. So every particle is inside,
// after trilinear interpolation, at any voxel size.
//
// Cost scales with the surface, not the volume: particles are binned per leaf (8^3 voxels); a
// leaf whose own and 26 neighbour bins each hold at least 3/4 of their rest count is deep inside
// (stored as an inactive tile at -w dx, never computed; cavities smaller than about a third of a
// leaf inside such dense fluid are not resolved). Every other leaf within the kernel's reach of a
// particle gathers the particles of its 27 neighbour bins and accumulates, per row of 8 voxels
// along z (a loop the compiler vectorises), the kernel sum and the nearest squared distance; the
// smoothing reads a leaf and a 2-voxel halo of its neighbours. Bins and particles are visited in
// a fixed order and every pass writes only its own leaf, so the grid is bit-identical for any
// thread count.
//
// Why not OpenVDB's ParticlesToLevelSet + LevelSetFilter themselves: measured here, 64k particles
// took 7 s (a union of spheres is a distance field only outside, so the interior stays active,
// and every filter pass renormalises it with WENO5), against about 0.1 s for a simulated frame.
#pragma once

#include <openvdb/openvdb.h>

#include <span>

namespace seiche::exporting {

struct SurfaceShape {
  float spacing = 0.02f;     ///< m, the fluid's rest particle spacing s
  float voxel_size = 0.01f;  ///< m, in [s/4, s] (the kernel must reach at most one leaf)
  float half_width = 3.0f;   ///< voxels, the narrow band's half width
  int smoothing_passes = 2;  ///< 0, 1 or 2 passes of the 3-voxel box filter (0: the raw field)
};

/// Kernel radius of the surface's density field, in units of the spacing.
inline constexpr float kSurfaceKernelRadius = 2.0f;
/// Particle sphere radius of the raw field, in units of the spacing.
inline constexpr float kParticleSphereRadius = 1.0f;
/// The raw field's shift inward before smoothing (the erosion), in units of the spacing: a
/// resting block's faces land 0.08 s outside it on average (0.325 would put them on it, but
/// would leave twice as many particles of a simulated surface to be lifted, which shows).
inline constexpr float kErosion = 0.25f;
/// Radius of the bead of spray left outside by the smoothing, in units of the spacing.
inline constexpr float kBeadRadius = 0.5f;

/// A uniform linear transform of voxel size `voxel_size`, voxel centres at integer multiples.
openvdb::math::Transform::Ptr voxel_transform(float voxel_size);

struct FluidSurfaceGrids {
  openvdb::FloatGrid::Ptr surface;   ///< GRID_LEVEL_SET, background w dx, negative inside
  openvdb::Vec3SGrid::Ptr velocity;  ///< kernel-weighted particle velocity on the surface's
                                     ///< active voxels within the kernel's reach of a particle
                                     ///< (the band outside reaches 2 s); null unless asked
};

/// The surface of the particles at (x[i], y[i], z[i]) (m), and with `with_velocity` the velocity
/// grid of the velocities (vx[i], vy[i], vz[i]) (m/s; ignored, and may be empty, without it).
/// Throws std::invalid_argument for a shape out of range or arrays of different lengths.
FluidSurfaceGrids fluid_surface(std::span<const float> x, std::span<const float> y,
                                std::span<const float> z, std::span<const float> vx,
                                std::span<const float> vy, std::span<const float> vz,
                                const SurfaceShape& shape, bool with_velocity);

}  // namespace seiche::exporting
