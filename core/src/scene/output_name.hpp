// Names that become parts of output file names: the scene's "name" (the fluid's .vdb and .obj
// frames, the default output folder out/<name>) and every cloth's "name" (its .obj frames).
// A scene is data a studio receives from others, so it must never choose where files land: a
// name is one plain file-name part, checked when the scene is read.
//
// The rule: 1 to 64 characters of the POSIX portable file name character set (ASCII letters,
// digits, '_', '-', '.'), not starting with '.' or '-'.
//   - The portable set has no path separator ('/', and '\' for Windows shares), no control
//     character (a newline in a name breaks every listing and script), no space or shell
//     metacharacter, and means the same on every file system a bake is copied to.
//   - No leading '.': "." and ".." are folders, not names, a dot-name is hidden, and ".<file>.tmp"
//     is the pattern of the temporary files the writers rename into place (and that a resumed
//     bake removes). No leading '-': a file "-x.0001.obj" reads as an option to rm, cp, tar.
//   - 64 characters: a file name <name>.<frame>.<ext> and its temporary twin stay far below
//     NAME_MAX (255 bytes), and listings stay readable.
// Two names write the same files when they are equal ignoring ASCII case: macOS and Windows
// file systems (and the network shares render farms read from) fold case, and the character set
// leaves no other folding (no Unicode normalization, no separators, no "./" prefixes).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace seiche::detail {

inline constexpr std::size_t kMaxOutputNameLength = 64;

/// The rule in words (key tables and messages).
inline constexpr std::string_view kOutputNameRule =
    "1 to 64 ASCII letters, digits, `_`, `-`, `.`; not starting with `.` or `-`";

/// What is wrong with `name` as an output file-name part, or "" when it is valid.
std::string output_name_problem(std::string_view name);

/// The form two names are compared in: equal forms write the same files (ASCII lower case).
std::string output_name_key(std::string_view name);

}  // namespace seiche::detail
