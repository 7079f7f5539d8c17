// Scene keys declared once: a key table lists the keys of one definition struct (SolverDef,
// FluidDef, ...), each with the member it fills, its range, unit, a rendered or written default
// and one line of documentation. read_keys() reads and checks an object against the table (type,
// range, required keys; JsonReader::finish() then rejects unknown keys), and key_docs() renders
// the same rows for the key tables of docs/scene-format.md (scene_format_doc.hpp).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <fmt/format.h>

#include "json_reader.hpp"

namespace seiche::detail {

/// One row of a rendered key table (docs/scene-format.md): every cell as markdown.
struct KeyDoc {
  std::string key, type, unit, default_value, valid, meaning;
};

/// A named key table of docs/scene-format.md: its rows go between the marker comments
/// `<!-- scene-keys: NAME -->` and `<!-- /scene-keys -->`.
struct KeyTableDoc {
  std::string name;
  std::vector<KeyDoc> rows;
};

/// Prefixes every row's key ("point" -> "plane.point") and appends the rows to `out`.
void append_prefixed(std::vector<KeyDoc>& out, std::string_view prefix, const std::vector<KeyDoc>& rows);

// Helpers for the rendering of a row's default and range (key_table.cpp).
std::string doc_number(float value);   ///< the shortest text that reads back: 0.02, 10000, -9.81
std::string doc_number(double value);
std::string doc_number(int value);
std::string doc_floats(const float* values, std::size_t count);         ///< [0, -9.81, 0]
std::string doc_ints(const int* values, std::size_t count);             ///< [32, 32]
std::string doc_range(const Range& range, bool integer);                ///< "≥ 0", "1 … 8", "in (0, 1)"
std::string doc_choices(const std::vector<std::string>& choices);       ///< `"a"`, `"b"` or `"c"`

/// A key of a definition struct `Def`.
template <class Def>
struct Key {
  /// The member the value goes to; monostate: a nested object or a special value that the
  /// section's reader reads itself (the table only records the key as known and documents it).
  using Member = std::variant<std::monostate, float Def::*, double Def::*, int Def::*, std::optional<int> Def::*,
                              bool Def::*, std::string Def::*, Vec3 Def::*, std::array<float, 2> Def::*,
                              std::array<int, 2> Def::*, std::vector<int> Def::*>;

  std::string_view name;
  Member member;
  Range range_ = {};
  bool required_ = false;
  std::vector<std::string> choices_;  ///< a string member: the allowed values
  std::string_view unit_ = "–";
  std::string_view doc_ = {};
  std::string_view type_ = {};         ///< monostate members: the type as documented
  std::string_view default_text_ = {}; ///< written default; empty: rendered from Def{}
  std::string_view valid_note_ = {};   ///< a rule beyond the range (checked in code after the table)

  Key(std::string_view key, Member m) : name(key), member(m) {}
  Key(std::string_view key, Member m, Range r) : name(key), member(m), range_(r) {}

  Key&& range(Range r) && { return range_ = r, std::move(*this); }
  Key&& required() && { return required_ = true, std::move(*this); }
  Key&& choices(std::vector<std::string> c) && { return choices_ = std::move(c), std::move(*this); }
  Key&& unit(std::string_view u) && { return unit_ = u, std::move(*this); }
  Key&& doc(std::string_view d) && { return doc_ = d, std::move(*this); }
  Key&& type(std::string_view t) && { return type_ = t, std::move(*this); }
  Key&& default_text(std::string_view d) && { return default_text_ = d, std::move(*this); }
  Key&& valid_note(std::string_view v) && { return valid_note_ = v, std::move(*this); }
};

/// A key the section's reader reads itself (a nested object, a set of flags): documented with
/// `type`, recorded as known by read_keys().
template <class Def>
Key<Def> nested(std::string_view key, std::string_view type) {
  return std::move(Key<Def>(key, std::monostate{}).type(type));
}

template <class Def>
using KeyTable = std::vector<Key<Def>>;

/// Reads every key of `table` present in `r` into `def` (absent keys keep def's value), checking
/// type and range: the optional keys in table order, then the required ones (all asked for
/// before any is read, so that a typo of a required key is reported as a typo). Nested keys are
/// only recorded as known. The caller calls r.finish() and then its checks across keys.
template <class Def>
void read_keys(JsonReader& r, const KeyTable<Def>& table, Def& def) {
  const auto read_one = [&](const Key<Def>& k) {
    std::visit(
        [&](auto member) {
          using M = decltype(member);
          if constexpr (std::is_same_v<M, std::monostate>) {
            r.has(k.name);
          } else if constexpr (std::is_same_v<M, std::optional<int> Def::*>) {
            if (r.has(k.name)) {
              int value = 0;
              r.read(k.name, value, k.range_);
              def.*member = value;
            }
          } else if constexpr (std::is_same_v<M, std::string Def::*>) {
            if (k.choices_.empty()) r.read(k.name, def.*member);
            else r.read_choice(k.name, def.*member, k.choices_);
          } else if constexpr (std::is_same_v<M, bool Def::*> || std::is_same_v<M, Vec3 Def::*>) {
            r.read(k.name, def.*member);
          } else {
            r.read(k.name, def.*member, k.range_);
          }
        },
        k.member);
  };
  for (const Key<Def>& k : table)
    if (!k.required_) read_one(k);
  for (const Key<Def>& k : table)
    if (k.required_) r.require(k.name);
  for (const Key<Def>& k : table)
    if (k.required_) read_one(k);
}

/// An object that has only the keys of `table`: read_keys() from `defaults`, then r.finish().
template <class Def>
Def read_object(JsonReader& r, const KeyTable<Def>& table, Def defaults = Def{}) {
  read_keys(r, table, defaults);
  r.finish();
  return defaults;
}

/// `text` as a Markdown code span. (fmt, not "`" + std::string + "`": g++ 12 reports a false
/// -Wrestrict on that concatenation.)
inline std::string code_span(std::string_view text) { return fmt::format("`{}`", text); }

/// The documentation rows of `table`; defaults are rendered from `defaults` (Def{} unless a
/// default depends on context) unless the row writes its own.
template <class Def>
std::vector<KeyDoc> key_docs(const KeyTable<Def>& table, const Def& defaults = Def{}) {
  std::vector<KeyDoc> rows;
  for (const Key<Def>& k : table) {
    KeyDoc row;
    row.key = code_span(k.name);
    row.unit = std::string(k.unit_);
    row.meaning = std::string(k.doc_);
    std::string range_text;
    std::visit(
        [&](auto member) {
          using M = decltype(member);
          if constexpr (std::is_same_v<M, std::monostate>) {
            row.type = std::string(k.type_);
          } else {
            const auto& value = defaults.*member;
            if constexpr (std::is_same_v<M, float Def::*> || std::is_same_v<M, double Def::*>) {
              row.type = std::is_same_v<M, float Def::*> ? "float" : "double";
              row.default_value = code_span(doc_number(value));
              range_text = doc_range(k.range_, false);
            } else if constexpr (std::is_same_v<M, int Def::*>) {
              row.type = "integer";
              row.default_value = code_span(doc_number(value));
              range_text = doc_range(k.range_, true);
            } else if constexpr (std::is_same_v<M, std::optional<int> Def::*>) {
              row.type = "integer";
              row.default_value = value ? code_span(doc_number(*value)) : "none";
              range_text = doc_range(k.range_, true);
            } else if constexpr (std::is_same_v<M, bool Def::*>) {
              row.type = "bool";
              row.default_value = value ? "`true`" : "`false`";
            } else if constexpr (std::is_same_v<M, std::string Def::*>) {
              row.type = "string";
              row.default_value = "`\"" + value + "\"`";
              range_text = k.choices_.empty() ? "" : doc_choices(k.choices_);
            } else if constexpr (std::is_same_v<M, Vec3 Def::*>) {
              row.type = "vec3";
              row.default_value = code_span(doc_floats(value.data(), 3));
              range_text = "finite";
            } else if constexpr (std::is_same_v<M, std::array<float, 2> Def::*>) {
              row.type = "2 floats";
              row.default_value = code_span(doc_floats(value.data(), 2));
              range_text = doc_range(k.range_, false);
            } else if constexpr (std::is_same_v<M, std::array<int, 2> Def::*>) {
              row.type = "2 integers";
              row.default_value = code_span(doc_ints(value.data(), 2));
              range_text = doc_range(k.range_, true);
            } else {
              row.type = "array of integers";
              row.default_value = code_span(doc_ints(value.data(), value.size()));
              range_text = doc_range(k.range_, true);
            }
          }
        },
        k.member);
    if (!k.default_text_.empty()) row.default_value = std::string(k.default_text_);
    if (k.required_) row.default_value = "**required**";
    row.valid = range_text.empty() || k.valid_note_.empty() ? range_text + std::string(k.valid_note_)
                                                            : range_text + ", " + std::string(k.valid_note_);
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace seiche::detail
