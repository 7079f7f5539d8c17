#include "scene_input.hpp"

#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "errors.hpp"
#include "seiche/memory_estimate.hpp"
#include "seiche/scene_loader.hpp"

namespace py = pybind11;

namespace seiche_py {

namespace {

std::string read_file_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  if (!in) throw_input_error(fmt::format("{}: cannot be read", file.string()));
  return s.str();
}

std::string json_dumps(const py::handle& value) { return py::module_::import("json").attr("dumps")(value).cast<std::string>(); }

}  // namespace

SceneInput scene_input(const py::object& scene, const py::object& base_dir) {
  SceneInput input;
  if (!base_dir.is_none()) input.base_dir = py::module_::import("os").attr("fspath")(base_dir).cast<std::string>();
  if (scene.is_none()) {
    input.text = seiche::default_scene_json();
    input.source = "<default scene>";
  } else if (py::isinstance<py::dict>(scene)) {
    input.text = json_dumps(scene);
    input.source = "<scene dict>";
  } else {
    input.file = py::module_::import("os").attr("fspath")(scene).cast<std::string>();
    input.source = input.file.string();
  }
  return input;
}

std::vector<std::string> scene_overrides(const py::object& set) {
  std::vector<std::string> overrides;
  if (set.is_none()) return overrides;
  if (py::isinstance<py::dict>(set)) {
    for (auto [key, value] : set.cast<py::dict>())
      overrides.push_back(py::str(key).cast<std::string>() + "=" + json_dumps(value));
    return overrides;
  }
  if (py::isinstance<py::str>(set)) return {set.cast<std::string>()};
  for (const py::handle& item : set) overrides.push_back(item.cast<std::string>());
  return overrides;
}

SceneLimits scene_limits(const py::object& max_memory, bool allow_huge_work) {
  SceneLimits limits;
  limits.allow_huge_work = allow_huge_work;
  if (max_memory.is_none()) return limits;
  const std::string text = py::str(max_memory).cast<std::string>();
  limits.max_memory = seiche::parse_memory_size(text);
  if (!limits.max_memory)
    throw_input_error(fmt::format("--max-memory: expected a size such as 512M, 8G or 1.5GiB, got \"{}\"", text));
  return limits;
}

seiche::SceneDef load_checked_scene(const SceneInput& input, const std::vector<std::string>& overrides,
                                    const SceneLimits& limits) {
  seiche::SceneDef scene;
  if (input.file.empty()) {
    scene = seiche::load_scene_text(input.text, input.source, overrides, input.base_dir);
  } else {
    scene = seiche::load_scene_file(input.file, overrides);
  }
  seiche::check_scene_memory(scene, input.source, limits.max_memory);
  seiche::check_scene_work(scene, input.source, limits.allow_huge_work);
  return scene;
}

std::string scene_json_text(const SceneInput& input) {
  return input.file.empty() ? input.text : read_file_text(input.file);
}

}  // namespace seiche_py
