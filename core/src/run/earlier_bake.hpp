// A new bake into a folder that holds an earlier bake. The new bake replaces the earlier one:
// it overwrites the frames of its own range, bake.json and the checkpoint; the earlier bake's
// frame files outside the new range would stay beside the new bake's as if they belonged to it
// (re-baking frames 1-20 into a folder of frames 1-40 would leave 21-40 of the old simulation
// after the new 20). So they are removed before the first frame.
//
// Only files the earlier bake provably wrote are removed: the folder's bake.json records the
// earlier bake's frame range, and a file goes only if its name is one this bake's writers give to
// a frame of that range outside the new one (particles.0031.ply, sail.0031.obj). Nothing else in
// the folder is touched: files of other names (an earlier scene's other cloths, renders), and
// everything when there is no readable bake.json (then a warning says the old frames are kept).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace seiche {

/// The file names a bake writes for one frame, relative to its folder.
using FrameFileNames = std::function<std::vector<std::string>(int frame)>;

/// Removes the earlier bake's frame files in `dir` outside [first_frame, last_frame] (see above);
/// notes what it removed (or why it could not tell) on `progress` when not null. Returns the
/// number of files removed. Throws IoError naming a file that cannot be removed.
std::size_t remove_earlier_bake_frames(const std::filesystem::path& dir, int first_frame, int last_frame,
                                       const FrameFileNames& frame_files, std::ostream* progress);

}  // namespace seiche
