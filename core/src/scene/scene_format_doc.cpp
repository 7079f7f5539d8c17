// Renders the readers' key tables into docs/scene-format.md between marker comments.
#include "scene_format_doc.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "scene_section.hpp"

namespace seiche::detail {

namespace {

constexpr std::string_view kOpen = "<!-- scene-keys: ";
constexpr std::string_view kOpenEnd = " -->";
constexpr std::string_view kClose = "<!-- /scene-keys -->";

std::string render_table(const std::vector<KeyDoc>& rows) {
  std::string out = "| Key | Type | Unit | Default | Valid | Meaning |\n|---|---|---|---|---|---|\n";
  for (const KeyDoc& r : rows)
    out += fmt::format("| {} | {} | {} | {} | {} | {} |\n", r.key, r.type, r.unit, r.default_value, r.valid, r.meaning);
  return out;
}

}  // namespace

std::string regenerate_scene_format(std::string_view doc) {
  const std::vector<KeyTableDoc> tables = scene_key_tables();
  std::vector<std::string> placed;
  std::string out;
  std::size_t pos = 0;
  while (true) {
    const std::size_t open = doc.find(kOpen, pos);
    if (open == std::string_view::npos) break;
    const std::size_t name_begin = open + kOpen.size();
    const std::size_t name_end = doc.find(kOpenEnd, name_begin);
    const std::size_t close = doc.find(kClose, name_begin);
    if (name_end == std::string_view::npos || close == std::string_view::npos || close < name_end)
      throw std::runtime_error("scene-format: a scene-keys marker without its end marker");
    const std::string name(doc.substr(name_begin, name_end - name_begin));
    const auto table = std::find_if(tables.begin(), tables.end(), [&](const KeyTableDoc& t) { return t.name == name; });
    if (table == tables.end()) throw std::runtime_error("scene-format: no key table named \"" + name + "\"");
    placed.push_back(name);
    out.append(doc.substr(pos, name_end + kOpenEnd.size() - pos));
    out += "\n\n" + render_table(table->rows) + "\n";  // blank lines: the comments stay out of the table
    pos = close;
  }
  out.append(doc.substr(pos));
  for (const KeyTableDoc& t : tables)
    if (std::count(placed.begin(), placed.end(), t.name) != 1)
      throw std::runtime_error("scene-format: the key table \"" + t.name + "\" must have exactly one place");
  return out;
}

}  // namespace seiche::detail
