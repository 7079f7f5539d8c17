// The rendering of key table rows for docs/scene-format.md: numbers, vectors, ranges and
// choices as the page writes them.
#include "key_table.hpp"

#include <fmt/format.h>

namespace seiche::detail {

void append_prefixed(std::vector<KeyDoc>& out, std::string_view prefix, const std::vector<KeyDoc>& rows) {
  for (KeyDoc row : rows) {
    // "`point`" -> "`plane.point`"
    row.key = fmt::format("`{}.{}", prefix, row.key.substr(1));
    out.push_back(std::move(row));
  }
}

std::string doc_number(float value) { return fmt::format("{}", value); }
std::string doc_number(double value) { return fmt::format("{}", value); }
std::string doc_number(int value) { return fmt::format("{}", value); }

namespace {
template <class T>
std::string doc_list(const T* values, std::size_t count) {
  std::string s = "[";
  for (std::size_t i = 0; i < count; ++i) s += (i ? ", " : "") + fmt::format("{}", values[i]);
  return s + "]";
}
}  // namespace

// Floats print as the shortest text that reads back to the same float (0.2f is "0.2").
std::string doc_floats(const float* values, std::size_t count) { return doc_list(values, count); }
std::string doc_ints(const int* values, std::size_t count) { return doc_list(values, count); }

std::string doc_range(const Range& range, bool integer) {
  const bool has_lo = range.lo != -Range::kInf, has_hi = range.hi != Range::kInf;
  if (!has_lo && !has_hi) return integer ? "" : "finite";
  if (!has_hi) return fmt::format("{} {}", range.lo_open ? ">" : "≥", range.lo);
  if (!has_lo) return fmt::format("{} {}", range.hi_open ? "<" : "≤", range.hi);
  if (integer && !range.lo_open && !range.hi_open) return fmt::format("{} … {}", range.lo, range.hi);
  return fmt::format("in {}{}, {}{}", range.lo_open ? '(' : '[', range.lo, range.hi, range.hi_open ? ')' : ']');
}

std::string doc_choices(const std::vector<std::string>& choices) {
  std::string s;
  for (std::size_t i = 0; i < choices.size(); ++i)
    s += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + fmt::format("`\"{}\"`", choices[i]);
  return s;
}

}  // namespace seiche::detail
