#include "seiche/output_files.hpp"

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "seiche/frame_exporter.hpp"

namespace seiche {

namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const char* what, int err) {
  throw IoError(fmt::format("{}: {}: {}", path.string(), what, std::strerror(err)));
}

// write_file_atomically's temporary twin of `path`: ".<name>.tmp" in the same folder.
std::filesystem::path temporary_twin(const std::filesystem::path& path) {
  return path.parent_path() / fmt::format(".{}.tmp", path.filename().string());
}

// Creates `probe` (a new file: no link is followed) and removes it; the errno of a failure, or 0.
int probe_create(const std::filesystem::path& probe) {
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) return errno;
  ::close(fd);
  ::unlink(probe.c_str());
  return 0;
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path tmp = temporary_twin(path);
  // O_NOFOLLOW: a symbolic link planted at the temporary name cannot redirect the bytes (the
  // rename below replaces a link at `path` itself instead of writing through it).
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) fail(path, "cannot create file", errno);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      fail(path, "cannot write", err);
    }
    done += std::size_t(n);
  }
  const int sync_error = ::fsync(fd) != 0 ? errno : 0;
  const int close_error = ::close(fd) != 0 ? errno : 0;
  if (sync_error != 0 || close_error != 0) {
    ::unlink(tmp.c_str());
    fail(path, "cannot flush to disk", sync_error != 0 ? sync_error : close_error);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    fail(path, "cannot rename the finished file into place", err);
  }
}

void prepare_output_directory(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(fmt::format("{}: cannot create output folder: {}", dir.string(), ec.message()));
  if (const int err = probe_create(dir / fmt::format(".seiche-write-test-{}.tmp", ::getpid())); err != 0)
    fail(dir, "output folder is not writable", err);
}

void check_output_file_writable(const std::filesystem::path& file) {
  std::error_code ec;
  const std::string name = file.filename().string();
  if (name.empty() || name == "." || name == ".." || std::filesystem::is_directory(file, ec))
    throw IoError(fmt::format("{}: is a folder; a file name is needed here", file.string()));
  const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : ".";
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(fmt::format("{}: cannot create its folder {}: {}", file.string(), dir.string(), ec.message()));
  if (const int err = probe_create(temporary_twin(dir / name)); err != 0) fail(file, "cannot create file", err);
}

void check_file_name_inside(const std::filesystem::path& dir, const std::filesystem::path& name) {
  const std::string text = name.string();
  if (text.empty() || name.is_absolute() || name.has_parent_path() || text == "." || text == ".." ||
      text.find('/') != std::string::npos)
    throw IoError(fmt::format("{}: the output file name \"{}\" is not a plain file name inside the folder; "
                              "nothing was written",
                              dir.string(), text));
}

void check_frame_files_inside(const FrameExporter& exporter, const std::filesystem::path& dir, int first_frame,
                              int last_frame) {
  for (const int frame : {first_frame, last_frame})
    for (const std::filesystem::path& name : exporter.files(frame)) check_file_name_inside(dir, name);
}

std::string encode_particles_ply(const ParticleStore& s) {
  const std::size_t n = s.size();
  std::string out = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment written by seiche\nelement vertex {}\n"
      "property float x\nproperty float y\nproperty float z\n"
      "property float vx\nproperty float vy\nproperty float vz\n"
      "property int id\nend_header\n",
      n);
  // The store is in cell order, exports are in id order.
  const std::vector<std::uint32_t> index_of_id = s.index_of_id();
  constexpr std::size_t kRecord = 6 * sizeof(float) + sizeof(std::int32_t);
  const std::size_t header = out.size();
  out.resize(header + n * kRecord);
  char* dst = out.data() + header;
  static_assert(std::endian::native == std::endian::little, "PLY writer assumes little-endian");
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::uint32_t i = index_of_id[k];
      const float v[6] = {s.x[i], s.y[i], s.z[i], s.vx[i], s.vy[i], s.vz[i]};
      std::memcpy(dst + k * kRecord, v, sizeof(v));
      std::memcpy(dst + k * kRecord + sizeof(v), &s.id[i], sizeof(std::int32_t));
    }
  });
  return out;
}

std::string frame_file_name(std::string_view stem, int frame, std::string_view extension) {
  return fmt::format("{}.{:04d}.{}", stem, frame, extension);
}

}  // namespace seiche
