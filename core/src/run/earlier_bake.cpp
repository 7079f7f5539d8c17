// Removing an earlier bake's frames outside a new bake's range (the rule: earlier_bake.hpp).
#include "earlier_bake.hpp"

#include <algorithm>
#include <fstream>
#include <limits>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <nlohmann/json.hpp>

#include "seiche/bake.hpp"
#include "seiche/output_files.hpp"

namespace seiche {

namespace fs = std::filesystem;

namespace {

// The frame range an earlier bake.json records, or the reason it cannot be read.
struct RecordedRange {
  std::optional<std::pair<int, int>> range;
  std::string problem;
};

RecordedRange recorded_frame_range(const fs::path& recipe_file) {
  std::ifstream in(recipe_file, std::ios::binary);
  if (!in) return {{}, "cannot be read"};
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  const auto frame = [&](const char* key) -> std::optional<int> {
    if (!doc.is_object() || !doc.contains(key) || !doc[key].is_number_integer()) return std::nullopt;
    const auto v = doc[key].get<std::int64_t>();
    if (v < 1 || v > std::numeric_limits<int>::max()) return std::nullopt;
    return static_cast<int>(v);
  };
  const auto first = frame("first_frame"), last = frame("last_frame");
  if (!first || !last || *first > *last) return {{}, "records no valid frame range"};
  return {std::pair{*first, *last}, {}};
}

// The frame number of a frame file's name ("sail.0031.obj" -> 31): the digits between its last
// two dots.
std::optional<int> frame_of(const std::string& name) {
  const auto ext = name.rfind('.');
  if (ext == std::string::npos || ext == 0) return std::nullopt;
  const auto start = name.rfind('.', ext - 1);
  if (start == std::string::npos) return std::nullopt;
  const std::string digits = name.substr(start + 1, ext - start - 1);
  if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  return std::stoi(digits);
}

}  // namespace

std::size_t remove_earlier_bake_frames(const fs::path& dir, int first_frame, int last_frame,
                                       const FrameFileNames& frame_files, std::ostream* progress) {
  const fs::path recipe_file = dir / kBakeRecipeFile;
  std::error_code ec;
  if (!fs::exists(recipe_file, ec)) return 0;
  const RecordedRange earlier = recorded_frame_range(recipe_file);
  if (!earlier.range) {
    if (progress)
      fmt::print(*progress,
                 "seiche: warning: {} of an earlier bake {}: its frame files in {} are left as they are\n",
                 recipe_file.string(), earlier.problem, dir.string());
    return 0;
  }
  const auto [old_first, old_last] = *earlier.range;
  // The folder is listed once (its size bounds the work, whatever range bake.json claims).
  std::vector<fs::path> stale;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::optional<int> frame = frame_of(name);
    if (!frame || *frame < old_first || *frame > old_last || (first_frame <= *frame && *frame <= last_frame))
      continue;
    const std::vector<std::string> names = frame_files(*frame);
    if (std::find(names.begin(), names.end(), name) != names.end() && !entry.is_directory(ec))
      stale.push_back(entry.path());
  }
  if (ec) throw IoError(fmt::format("{}: cannot list the folder: {}", dir.string(), ec.message()));
  std::sort(stale.begin(), stale.end());
  for (const fs::path& file : stale)
    if (!fs::remove(file, ec) && ec)
      throw IoError(fmt::format("{}: cannot remove this frame of the earlier bake (frames {}-{}), which would be "
                                "left beside the new bake's frames {}-{}: {}",
                                file.string(), old_first, old_last, first_frame, last_frame, ec.message()));
  if (progress && !stale.empty())
    fmt::print(*progress,
               "removed {} frame files of the earlier bake in {} (its frames {}-{}; this bake writes {}-{})\n",
               stale.size(), dir.string(), old_first, old_last, first_frame, last_frame);
  return stale.size();
}

}  // namespace seiche
