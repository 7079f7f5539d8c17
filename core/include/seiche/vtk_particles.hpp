// The particles for ParaView: VTK's XML PolyData (.vtp), one file per frame, with the velocity
// and the id as point arrays, and a .pvd collection that lists the frames with their simulated
// times, so that ParaView opens the whole sequence as one time series in one step (its PLY
// reader keeps the positions only). The encoding and its reasons: vtk_particles.cpp.
#pragma once

#include <string>
#include <string_view>

#include "seiche/particle_store.hpp"

namespace seiche {

/// One frame as VTK XML PolyData, version 1.0, little endian, appended raw binary with UInt64
/// block headers: Points (Float32 x3), the point arrays `velocity` (Float32 x3) and `id`
/// (Int32), and one vertex cell per point (Verts: Int32 connectivity 0..n-1, offsets 1..n), in
/// id order like the PLY. A store without particles gives a valid file with no points.
std::string encode_particles_vtp(const ParticleStore& store);

/// The .pvd collection of the frames first_frame..last_frame of `<stem>.%04d.vtp` (none when
/// last_frame < first_frame), each with its simulated time frame * frame_dt (s) as `timestep`,
/// written to the shortest text that reads back as the same double.
std::string encode_particle_series_pvd(std::string_view stem, int first_frame, int last_frame, double frame_dt);

}  // namespace seiche
