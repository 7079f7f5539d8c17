// JsonReader: reads one JSON object into typed values while keeping the JSON path of every value
// at hand, so that each error can say where it is ("fluids[0].spacing: must be > 0, got -0.1").
// Every key a read asks about is recorded as known; finish() rejects the keys nobody asked about
// and suggests the closest known one. Internal to core: the scene loader is its only user.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "seiche/scene.hpp"

namespace seiche::detail {

using Json = nlohmann::json;

/// The interval a number must lie in; unbounded unless built by one of the named constructors.
struct Range {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo = -kInf;
  double hi = kInf;
  bool lo_open = false;
  bool hi_open = false;

  static Range at_least(double lo) { return {lo, kInf, false, false}; }          // [lo, inf)
  static Range above(double lo) { return {lo, kInf, true, false}; }              // (lo, inf)
  static Range closed(double lo, double hi) { return {lo, hi, false, false}; }   // [lo, hi]
  static Range open(double lo, double hi) { return {lo, hi, true, true}; }       // (lo, hi)
  static Range half_open(double lo, double hi) { return {lo, hi, false, true}; } // [lo, hi)
  static Range left_open(double lo, double hi) { return {lo, hi, true, false}; } // (lo, hi]

  bool contains(double v) const;
  std::string describe() const;  ///< ">= 1", "> 0", "in [0, 1]", "in (0, 1)"
};

/// "" (the document itself) is shown as "(root)".
std::string display_path(const std::string& path);
std::string member_path(const std::string& parent, std::string_view key);  ///< "solver" + "substeps"
std::string element_path(const std::string& parent, std::size_t index);    ///< "fluids" + 0 -> "fluids[0]"

/// Throws SceneError(file, display_path(path), problem).
[[noreturn]] void fail(const std::string& file, const std::string& path, std::string problem);

/// A short description of a JSON value for "got ..." in messages: `string "nan"`, `array`, `3.5`.
std::string describe_value(const Json& value);

/// The known key closest to `key` by edit distance, if it is close enough to be a likely typo.
std::optional<std::string> closest_key(std::string_view key, const std::vector<std::string>& known);

class JsonReader {
 public:
  /// `node` and `file` must outlive the reader. Throws SceneError if `node` is not an object.
  JsonReader(const Json& node, std::string path, const std::string& file);

  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }
  std::string path_of(std::string_view key) const { return member_path(path_, key); }

  [[noreturn]] void fail_here(std::string problem) const;
  [[noreturn]] void fail_at(std::string_view key, std::string problem) const;

  /// Whether the key is present (recording it as known).
  bool has(std::string_view key);
  /// Throws "required key is missing" if absent, or "unknown key; did you mean ..." when a key
  /// nobody asked about looks like a typo of it. Check required keys after the optional reads of
  /// the object, so that the optional keys are known by then and not taken for typos.
  void require(std::string_view key);

  // Each read records the key as known and leaves `out` untouched (its default) when the key is
  // absent. Numbers must be finite after conversion to the member's type and lie in `range`.
  void read(std::string_view key, float& out, Range range = {});
  void read(std::string_view key, double& out, Range range = {});
  void read(std::string_view key, int& out, Range range = {});  ///< integral values only
  void read(std::string_view key, bool& out);
  void read(std::string_view key, std::string& out);
  /// A string that must be one of `allowed`.
  void read_choice(std::string_view key, std::string& out, const std::vector<std::string>& allowed);
  /// An array of distinct strings, each one of `allowed`; the result replaces `out`.
  void read_string_set(std::string_view key, std::vector<std::string>& out,
                       const std::vector<std::string>& allowed);
  void read(std::string_view key, Vec3& out);  ///< an array of exactly 3 finite floats
  /// An array of exactly 2 numbers, each in `range`.
  void read(std::string_view key, std::array<float, 2>& out, Range range = {});
  void read(std::string_view key, std::array<int, 2>& out, Range range = {});
  /// An array of integers (any length), each in `range`.
  void read(std::string_view key, std::vector<int>& out, Range range = {});

  /// A nested object that must be present (see require() on when to ask for it).
  JsonReader object(std::string_view key);
  /// A nested object that may be absent.
  std::optional<JsonReader> optional_object(std::string_view key);
  /// An array of objects, one reader per entry; empty when the key is absent.
  std::vector<JsonReader> objects(std::string_view key);

  /// Rejects every key of the object that no read asked about ("unknown key; did you mean ...").
  void finish() const;

 private:
  const Json* find(std::string_view key);  // records the key as known
  [[noreturn]] void fail_missing(std::string_view key) const;

  const Json* node_;
  std::string path_;
  const std::string* file_;
  std::vector<std::string> known_;
};

}  // namespace seiche::detail
