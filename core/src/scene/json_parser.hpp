// Step 1 of loading a scene: JSON text -> a JSON document, in time linear in the text's size,
// refusing a key that appears twice in one object (nlohmann would keep the last one without a
// word; a scene with two "fluids" arrays is a mistake). Errors name the file, the JSON path of
// the duplicate key, or the line and column of malformed text. Internal to core.
#pragma once

#include <string>
#include <string_view>

#include "json_reader.hpp"

namespace seiche::detail {

/// Throws SceneError(file, path, problem): "(root)" and "malformed JSON at line L, column C: ..."
/// for malformed text, the key's path and "duplicate key; ..." for a key seen twice in an object.
Json parse_json(std::string_view text, const std::string& file);

}  // namespace seiche::detail
