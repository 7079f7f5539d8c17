// The key tables of docs/scene-format.md, generated from the readers' key tables: every table
// sits between `<!-- scene-keys: NAME -->` and `<!-- /scene-keys -->`, and the prose around them
// is kept as written.
#pragma once

#include <string>
#include <string_view>

namespace seiche::detail {

/// `doc` with the text between every pair of markers replaced by the named table, rendered as
/// markdown (Key | Type | Unit | Default | Valid | Meaning). Throws std::runtime_error for a
/// marker that names no table, a marker without its end, or a table that has no marker.
std::string regenerate_scene_format(std::string_view doc);

}  // namespace seiche::detail
