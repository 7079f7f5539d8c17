// The output name rule (output_name.hpp): the check and the comparison form.
#include "output_name.hpp"

#include <fmt/format.h>

namespace seiche::detail {

namespace {

bool portable_file_name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
         c == '.';
}

// A character as a message shows it: 'x', or its code for anything invisible ("byte 0x0a").
std::string describe_char(char c) {
  const auto byte = static_cast<unsigned char>(c);
  if (byte == '\n') return "a newline";
  if (byte == '/' || byte == '\\') return fmt::format("'{}', a path separator,", c);
  if (byte > 0x20 && byte < 0x7f) return fmt::format("'{}'", c);
  if (byte == ' ') return "a space";
  return fmt::format("byte 0x{:02x}", byte);
}

}  // namespace

std::string output_name_problem(std::string_view name) {
  const std::string rule = fmt::format("it names output files, so it must be {}", kOutputNameRule);
  if (name.empty()) return fmt::format("must not be empty: {}", rule);
  if (name.size() > kMaxOutputNameLength)
    return fmt::format("is {} characters long, more than {}: {}", name.size(), kMaxOutputNameLength, rule);
  if (name == "." || name == "..")
    return fmt::format("\"{}\" is a folder, not a name: {}", name, rule);
  // The name itself is not shown here: it may hold a newline or a terminal control sequence.
  for (std::size_t i = 0; i < name.size(); ++i)
    if (!portable_file_name_char(name[i]))
      return fmt::format("contains {} at character {}: {}", describe_char(name[i]), i + 1, rule);
  if (name.front() == '.' || name.front() == '-')
    return fmt::format("\"{}\" starts with '{}': {}", name, name.front(), rule);
  return {};
}

std::string output_name_key(std::string_view name) {
  std::string key(name);
  for (char& c : key)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return key;
}

}  // namespace seiche::detail
