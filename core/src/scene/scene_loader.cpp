// Scene loading in three steps: parse the text (rejecting duplicate keys), apply the command-line
// overrides to the JSON document, then read the document section by section into a SceneDef with
// every value checked: the reader registry (scene_section.hpp) names each section's reader, key
// table and checks across sections, which run after all sections are read. docs/scene-format.md's
// key tables are generated from the same key tables (scene_format_doc.hpp).
#include "seiche/scene_loader.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <memory>
#include <system_error>

#include <fmt/format.h>

#include "json_parser.hpp"
#include "json_reader.hpp"
#include "scene_section.hpp"

namespace seiche {

SceneError::SceneError(std::string file, std::string json_path, std::string problem)
    : std::runtime_error(file + ": " + json_path + ": " + problem),
      file_(std::move(file)),
      json_path_(std::move(json_path)),
      problem_(std::move(problem)) {}

namespace {

using detail::Json;
using detail::JsonReader;
using detail::element_path;
using detail::fail;
using detail::member_path;
using detail::parse_json;

const std::string kCommandLine = "(command line)";

// ---- Step 1: parse (json_parser.hpp) --------------------------------------------------------

// ---- Step 2: overrides -----------------------------------------------------------------------

struct PathStep {
  std::string key;                   // an object member, or
  std::optional<std::size_t> index;  // an array element
};

// "fluids[0].box.min", "fluids.0.box.min" -> fluids, [0], box, min. A segment of digits after a
// dot is an index: no key of the scene format is a number.
std::vector<PathStep> parse_override_key(const std::string& key, const std::string& override_text) {
  const auto malformed = [&](std::string_view why) {
    fail(kCommandLine, key, fmt::format("malformed override \"{}\": {}", override_text, why));
  };
  const auto parse_index = [&](std::string_view digits) {
    std::size_t index = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), index);
    if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size())
      malformed(fmt::format("\"{}\" is not an array index", digits));
    return index;
  };

  std::vector<PathStep> steps;
  std::size_t i = 0;
  while (i < key.size()) {
    if (key[i] == '[') {
      if (steps.empty()) malformed("the key must start with a name");
      const auto close = key.find(']', i);
      if (close == std::string::npos) malformed("'[' without ']'");
      steps.push_back({{}, parse_index(std::string_view(key).substr(i + 1, close - i - 1))});
      i = close + 1;
    } else {
      const auto end = std::min(key.find_first_of(".[", i), key.size());
      const std::string_view name = std::string_view(key).substr(i, end - i);
      if (name.empty()) malformed("empty name in the key");
      const bool digits = std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; });
      if (digits && steps.empty()) malformed("the key must start with a name");
      steps.push_back(digits ? PathStep{{}, parse_index(name)} : PathStep{std::string(name), {}});
      i = end;
    }
    if (i < key.size() && key[i] == '.') {
      ++i;
      if (i == key.size() || key[i] == '[' || key[i] == '.') malformed("a '.' must be followed by a name or index");
    } else if (i < key.size() && key[i] != '[') {
      malformed(fmt::format("unexpected '{}'", key[i]));
    }
  }
  if (steps.empty()) malformed("empty key");
  return steps;
}

// Sets one value, creating missing objects on the way; an array index must exist already. The
// value is then read and checked like any other, so a mistyped key fails as an unknown key.
void apply_override(Json& root, const std::string& override_text) {
  const auto eq = override_text.find('=');
  if (eq == std::string::npos)
    fail(kCommandLine, override_text, fmt::format("malformed override \"{}\": expected KEY=VALUE", override_text));
  const std::string key = override_text.substr(0, eq);
  const std::string value_text = override_text.substr(eq + 1);
  const std::vector<PathStep> steps = parse_override_key(key, override_text);

  Json value = Json::parse(value_text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) value = value_text;  // not JSON: a plain string

  Json* node = &root;
  std::string path;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const PathStep& step = steps[s];
    const bool last = s + 1 == steps.size();
    if (step.index) {
      const std::size_t index = *step.index;
      if (!node->is_array())
        fail(kCommandLine, path, fmt::format("is {}, not an array; cannot set element {} (override \"{}\")",
                                             detail::describe_value(*node), index, override_text));
      if (index >= node->size())
        fail(kCommandLine, element_path(path, index),
             fmt::format("index {} is past the end of {} ({} {}; override \"{}\")", index,
                         detail::display_path(path), node->size(), node->size() == 1 ? "entry" : "entries",
                         override_text));
      node = &(*node)[index];
      path = element_path(path, index);
    } else {
      if (!node->is_object())
        fail(kCommandLine, path, fmt::format("is {}, not an object; cannot set \"{}\" (override \"{}\")",
                                             detail::describe_value(*node), step.key, override_text));
      if (!node->contains(step.key)) {
        if (!last && steps[s + 1].index)
          fail(kCommandLine, element_path(member_path(path, step.key), *steps[s + 1].index),
               fmt::format("index {} is past the end: {} is absent (override \"{}\")", *steps[s + 1].index,
                           member_path(path, step.key), override_text));
        (*node)[step.key] = Json::object();
      }
      node = &(*node)[step.key];
      path = member_path(path, step.key);
    }
    if (last) *node = value;
  }
}

// ---- Step 3: read the sections (the registry: scene_section.hpp) ----------------------------

SceneDef read_scene(const Json& document, const std::string& file, const std::string& default_name,
                    const std::filesystem::path& base_dir) {
  SceneDef scene;
  scene.name = default_name;
  scene.base_dir = base_dir.string();
  detail::read_scene_sections(JsonReader(document, "", file), scene);
  return scene;
}

SceneDef load_scene(std::string_view text, const std::string& file, std::span<const std::string> overrides,
                    const std::string& default_name, const std::filesystem::path& base_dir) {
  Json document = parse_json(text, file);
  if (!document.is_object())
    fail(file, "", "expected a JSON object at the top, got " + detail::describe_value(document));
  for (const std::string& o : overrides) apply_override(document, o);
  return read_scene(document, file, default_name, base_dir);
}

// What a path that is not a regular file is, for the message.
std::string_view kind_of_file(std::filesystem::file_type type) {
  switch (type) {
    case std::filesystem::file_type::directory: return "a directory";
    case std::filesystem::file_type::character: return "a character device";
    case std::filesystem::file_type::block: return "a block device";
    case std::filesystem::file_type::fifo: return "a FIFO (named pipe)";
    case std::filesystem::file_type::socket: return "a socket";
    default: return "of an unknown kind";
  }
}

// `size`: "1073741824 bytes"
[[noreturn]] void fail_too_large(const std::string& file, const std::string& size) {
  fail(file, "(file)", fmt::format("cannot open: it holds {}, over the limit of {} bytes ({} MiB) for a scene file",
                                   size, kMaxSceneFileBytes, kMaxSceneFileBytes >> 20));
}

// The file's text. Refused before reading anything: a path that is not a regular file (a device
// such as /dev/zero, a FIFO that might never end, a directory) and a file over
// kMaxSceneFileBytes. The read stops past the limit too, in case the file grows meanwhile.
std::string read_file(const std::filesystem::path& path, const std::string& file) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);  // follows links
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    fail(file, "(file)", fmt::format("cannot open: not a regular file (it is {})", kind_of_file(status.type())));
  if (std::filesystem::is_regular_file(status)) {
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxSceneFileBytes) fail_too_large(file, fmt::format("{} bytes", size));
  }
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) fail(file, "(file)", "cannot open: " + std::generic_category().message(errno));
  std::string text;
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, f.get())) > 0) {
    text.append(buffer, n);
    if (text.size() > kMaxSceneFileBytes) fail_too_large(file, fmt::format("{} bytes or more", text.size()));
  }
  if (std::ferror(f.get())) fail(file, "(file)", "cannot read: " + std::generic_category().message(errno));
  return text;
}

}  // namespace

SceneDef load_scene_text(std::string_view json_text, std::string_view source,
                         std::span<const std::string> overrides, const std::filesystem::path& base_dir) {
  return load_scene(json_text, std::string(source), overrides, SceneDef{}.name, base_dir);
}

SceneDef load_scene_file(const std::filesystem::path& file, std::span<const std::string> overrides) {
  const std::string source = file.string();
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::absolute(file, ec).parent_path();
  return load_scene(read_file(file, source), source, overrides, file.stem().string(), dir);
}

}  // namespace seiche
