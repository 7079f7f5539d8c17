// The test process's own temporary folder: <temp>/seiche_tests_<pid>, created on first use and
// removed (with everything in it) when the process ends. Tests write their files under it, so
// that two test runs at once on one machine, or ctest's parallel processes of one binary, never
// write the same path.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace seiche::testing_support {

inline const std::filesystem::path& process_temp_dir() {
  struct Folder {
    pid_t owner = ::getpid();
    std::filesystem::path path = std::filesystem::temp_directory_path() / ("seiche_tests_" + std::to_string(owner));
    Folder() {
      std::filesystem::remove_all(path);  // left by a crashed process that had the same id
      std::filesystem::create_directories(path);
    }
    ~Folder() {
      if (::getpid() != owner) return;  // a forked child that exits leaves its parent's folder alone
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Folder folder;
  return folder.path;
}

/// `name` (a file or folder name) within the process's temporary folder.
inline std::filesystem::path temp_path(const std::string& name) { return process_temp_dir() / name; }

}  // namespace seiche::testing_support
