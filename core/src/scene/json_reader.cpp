#include "json_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "seiche/scene_loader.hpp"

namespace seiche::detail {

// ---- Paths, messages -------------------------------------------------------------------------

bool Range::contains(double v) const {
  const bool above_lo = lo_open ? v > lo : v >= lo;
  const bool below_hi = hi_open ? v < hi : v <= hi;
  return above_lo && below_hi;
}

std::string Range::describe() const {
  if (lo == -kInf && hi == kInf) return "finite";
  if (hi == kInf) return fmt::format("{} {}", lo_open ? ">" : ">=", lo);
  if (lo == -kInf) return fmt::format("{} {}", hi_open ? "<" : "<=", hi);
  return fmt::format("in {}{}, {}{}", lo_open ? '(' : '[', lo, hi, hi_open ? ')' : ']');
}

std::string display_path(const std::string& path) { return path.empty() ? "(root)" : path; }

std::string member_path(const std::string& parent, std::string_view key) {
  return parent.empty() ? std::string(key) : fmt::format("{}.{}", parent, key);
}

std::string element_path(const std::string& parent, std::size_t index) {
  return fmt::format("{}[{}]", parent, index);
}

void fail(const std::string& file, const std::string& path, std::string problem) {
  throw SceneError(file, display_path(path), std::move(problem));
}

std::string describe_value(const Json& value) {
  switch (value.type()) {
    case Json::value_t::string: {
      const auto& s = value.get_ref<const std::string&>();
      constexpr std::size_t kShown = 40;
      return s.size() <= kShown ? fmt::format("string \"{}\"", s)
                                : fmt::format("string \"{}...\"", s.substr(0, kShown));
    }
    case Json::value_t::array: return fmt::format("array of {} elements", value.size());
    case Json::value_t::object: return "object";
    case Json::value_t::null: return "null";
    case Json::value_t::boolean: return fmt::format("boolean {}", value.get<bool>());
    default: return value.dump();  // numbers
  }
}

namespace {

// Optimal string alignment distance (Levenshtein plus adjacent transpositions), case-insensitive.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  const auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

std::string join_keys(const std::vector<std::string>& keys) {
  std::string out;
  for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
  return out;
}

// ---- Conversions: a JSON value at `path` -> a checked C++ value -------------------------------

double to_double(const Json& v, const std::string& path, const std::string& file, Range range) {
  if (!v.is_number()) fail(file, path, "expected a number, got " + describe_value(v));
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(file, path, fmt::format("must be finite, got {}", d));
  if (!range.contains(d)) fail(file, path, fmt::format("must be {}, got {}", range.describe(), d));
  return d;
}

float to_float(const Json& v, const std::string& path, const std::string& file, Range range = {}) {
  if (!v.is_number()) fail(file, path, "expected a number, got " + describe_value(v));
  const double d = v.get<double>();
  // Checked before the cast: converting a double beyond the float range is undefined behavior.
  if (!std::isfinite(d) || std::abs(d) > std::numeric_limits<float>::max())
    fail(file, path, fmt::format("{} is not finite as a 32-bit float (magnitude above {})", d,
                                 std::numeric_limits<float>::max()));
  const float f = static_cast<float>(d);
  if (!range.contains(f)) fail(file, path, fmt::format("must be {}, got {}", range.describe(), f));
  return f;
}

int to_int(const Json& v, const std::string& path, const std::string& file, Range range) {
  if (!v.is_number()) fail(file, path, "expected an integer, got " + describe_value(v));
  const double d = v.get<double>();  // exact for every int; a rough value is enough to reject
  if (v.is_number_float() && (!std::isfinite(d) || d != std::floor(d)))
    fail(file, path, "expected an integer, got " + describe_value(v));
  if (d < std::numeric_limits<int>::min() || d > std::numeric_limits<int>::max())
    fail(file, path, fmt::format("{} is outside the range of a 32-bit integer", v.dump()));
  const int i = v.is_number_float() ? static_cast<int>(d) : static_cast<int>(v.get<std::int64_t>());
  if (!range.contains(i)) fail(file, path, fmt::format("must be {}, got {}", range.describe(), i));
  return i;
}

}  // namespace

std::optional<std::string> closest_key(std::string_view key, const std::vector<std::string>& known) {
  std::optional<std::string> best;
  std::size_t best_distance = 0;
  for (const auto& candidate : known) {
    const std::size_t distance = edit_distance(key, candidate);
    // A third of the shorter name, at least one edit: "iteratons" -> "iterations", not "x" -> "mass".
    const std::size_t allowed = std::max<std::size_t>(1, std::min(key.size(), candidate.size()) / 3);
    if (distance <= allowed && (!best || distance < best_distance)) {
      best = candidate;
      best_distance = distance;
    }
  }
  return best;
}

// ---- JsonReader ------------------------------------------------------------------------------

JsonReader::JsonReader(const Json& node, std::string path, const std::string& file)
    : node_(&node), path_(std::move(path)), file_(&file) {
  if (!node.is_object()) fail(file, path_, "expected an object, got " + describe_value(node));
}

void JsonReader::fail_here(std::string problem) const { fail(*file_, path_, std::move(problem)); }

void JsonReader::fail_at(std::string_view key, std::string problem) const {
  fail(*file_, path_of(key), std::move(problem));
}

const Json* JsonReader::find(std::string_view key) {
  if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.emplace_back(key);
  const auto it = node_->find(key);
  return it == node_->end() ? nullptr : &*it;
}

bool JsonReader::has(std::string_view key) { return find(key) != nullptr; }

void JsonReader::require(std::string_view key) {
  if (!find(key)) fail_missing(key);
}

void JsonReader::read(std::string_view key, float& out, Range range) {
  if (const Json* v = find(key)) out = to_float(*v, path_of(key), *file_, range);
}

void JsonReader::read(std::string_view key, double& out, Range range) {
  if (const Json* v = find(key)) out = to_double(*v, path_of(key), *file_, range);
}

void JsonReader::read(std::string_view key, int& out, Range range) {
  if (const Json* v = find(key)) out = to_int(*v, path_of(key), *file_, range);
}

void JsonReader::read(std::string_view key, std::string& out) {
  const Json* v = find(key);
  if (!v) return;
  if (!v->is_string()) fail_at(key, "expected a string, got " + describe_value(*v));
  out = v->get<std::string>();
}

void JsonReader::read(std::string_view key, bool& out) {
  const Json* v = find(key);
  if (!v) return;
  if (!v->is_boolean()) fail_at(key, "expected true or false, got " + describe_value(*v));
  out = v->get<bool>();
}

namespace {
std::string quoted_list(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "\"" : i + 1 == names.size() ? " or \"" : ", \"") + names[i] + "\"";
  return s;
}
}  // namespace

void JsonReader::read_choice(std::string_view key, std::string& out, const std::vector<std::string>& allowed) {
  std::string value = out;
  read(key, value);
  if (std::find(allowed.begin(), allowed.end(), value) == allowed.end())
    fail_at(key, fmt::format("\"{}\" is not one of {}", value, quoted_list(allowed)));
  out = value;
}

void JsonReader::read_string_set(std::string_view key, std::vector<std::string>& out,
                                 const std::vector<std::string>& allowed) {
  const Json* v = find(key);
  if (!v) return;
  const std::string path = path_of(key);
  if (!v->is_array()) fail(*file_, path, "expected an array of strings, got " + describe_value(*v));
  std::vector<std::string> result;
  for (std::size_t i = 0; i < v->size(); ++i) {
    const Json& e = (*v)[i];
    if (!e.is_string()) fail(*file_, element_path(path, i), "expected a string, got " + describe_value(e));
    const std::string name = e.get<std::string>();
    if (std::find(allowed.begin(), allowed.end(), name) == allowed.end())
      fail(*file_, element_path(path, i), fmt::format("\"{}\" is not one of {}", name, quoted_list(allowed)));
    if (std::find(result.begin(), result.end(), name) != result.end())
      fail(*file_, element_path(path, i), fmt::format("\"{}\" is listed twice", name));
    result.push_back(name);
  }
  out = std::move(result);
}

void JsonReader::read(std::string_view key, Vec3& out) {
  const Json* v = find(key);
  if (!v) return;
  const std::string path = path_of(key);
  if (!v->is_array()) fail(*file_, path, "expected an array of 3 numbers, got " + describe_value(*v));
  if (v->size() != 3) fail(*file_, path, fmt::format("expected 3 numbers, got {}", v->size()));
  Vec3 result;
  for (std::size_t i = 0; i < 3; ++i) result[i] = to_float((*v)[i], element_path(path, i), *file_);
  out = result;
}

namespace {
// An array of `count` elements (0 = any length) converted one by one.
template <class T, class Convert>
std::vector<T> read_array(const Json& v, const std::string& path, const std::string& file, std::size_t count,
                          Convert convert) {
  if (!v.is_array()) {
    const std::string what = count ? fmt::format("an array of {} numbers", count) : std::string("an array of integers");
    fail(file, path, "expected " + what + ", got " + describe_value(v));
  }
  if (count && v.size() != count) fail(file, path, fmt::format("expected {} numbers, got {}", count, v.size()));
  std::vector<T> result;
  result.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) result.push_back(convert(v[i], element_path(path, i)));
  return result;
}
}  // namespace

void JsonReader::read(std::string_view key, std::array<float, 2>& out, Range range) {
  const Json* v = find(key);
  if (!v) return;
  const auto a = read_array<float>(*v, path_of(key), *file_, 2,
                                   [&](const Json& e, const std::string& p) { return to_float(e, p, *file_, range); });
  out = {a[0], a[1]};
}

void JsonReader::read(std::string_view key, std::array<int, 2>& out, Range range) {
  const Json* v = find(key);
  if (!v) return;
  const auto a = read_array<int>(*v, path_of(key), *file_, 2,
                                 [&](const Json& e, const std::string& p) { return to_int(e, p, *file_, range); });
  out = {a[0], a[1]};
}

void JsonReader::read(std::string_view key, std::vector<int>& out, Range range) {
  const Json* v = find(key);
  if (!v) return;
  out = read_array<int>(*v, path_of(key), *file_, 0,
                        [&](const Json& e, const std::string& p) { return to_int(e, p, *file_, range); });
}

JsonReader JsonReader::object(std::string_view key) {
  const Json* v = find(key);
  if (!v) fail_missing(key);
  return JsonReader(*v, path_of(key), *file_);
}

std::optional<JsonReader> JsonReader::optional_object(std::string_view key) {
  const Json* v = find(key);
  if (!v) return std::nullopt;
  return JsonReader(*v, path_of(key), *file_);
}

std::vector<JsonReader> JsonReader::objects(std::string_view key) {
  const Json* v = find(key);
  if (!v) return {};
  const std::string path = path_of(key);
  if (!v->is_array()) fail(*file_, path, "expected an array of objects, got " + describe_value(*v));
  std::vector<JsonReader> entries;
  entries.reserve(v->size());
  for (std::size_t i = 0; i < v->size(); ++i) entries.emplace_back((*v)[i], element_path(path, i), *file_);
  return entries;
}

void JsonReader::finish() const {
  for (const auto& [key, value] : node_->items()) {
    if (std::find(known_.begin(), known_.end(), key) != known_.end()) continue;
    const auto hint = closest_key(key, known_);
    fail_at(key, hint ? fmt::format("unknown key; did you mean \"{}\"?", *hint)
                      : fmt::format("unknown key; the keys here are: {}", join_keys(known_)));
  }
}

void JsonReader::fail_missing(std::string_view key) const {
  // A present key that looks like the missing one is a typo: report it rather than the absence.
  for (const auto& [present, value] : node_->items()) {
    const bool is_known = std::find(known_.begin(), known_.end(), present) != known_.end();
    if (!is_known && closest_key(present, {std::string(key)}))
      fail_at(present, fmt::format("unknown key; did you mean \"{}\"?", key));
  }
  fail_at(key, "required key is missing");
}

}  // namespace seiche::detail
