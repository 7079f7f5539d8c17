// Checkpoint files: encoding, verification and restoring. The layout is written at the top of
// checkpoint.hpp; this file keeps the reader as strict as the writer is simple: every size is
// checked before it is used, so a damaged file gives a message, never a crash.
#include "seiche/checkpoint.hpp"

#include <fmt/format.h>

#include <bit>
#include <cerrno>
#include <cstring>
#include <span>
#include <fstream>
#include <sstream>
#include <vector>

#include "seiche/simulation.hpp"

namespace seiche {

namespace {

static_assert(std::endian::native == std::endian::little, "checkpoints are written little-endian");

constexpr char kMagic[8] = {'S', 'E', 'I', 'C', 'H', 'E', 'C', 'P'};
constexpr std::uint32_t kFormatVersion = 2;
constexpr std::uint32_t kColumnCount = 12;  // x y z px py pz vx vy vz w phase id
constexpr std::size_t kPreambleBytes = sizeof(kMagic) + 4 + 8 + 8;

template <class T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <class T>
void put_column(std::string& out, const AlignedColumn<T>& column, std::size_t n) {
  out.append(reinterpret_cast<const char*>(column.data()), n * sizeof(T));
}

// Reads the body front to back; running past its end is a truncated (or lying) file.
class BodyReader {
 public:
  BodyReader(std::string_view bytes, const std::filesystem::path& file)
      : bytes_(bytes), file_(file) {}

  template <class T>
  T get(const char* what) {
    T value;
    take(&value, sizeof(T), what);
    return value;
  }
  std::string get_string(const char* what) {
    const auto size = get<std::uint32_t>(what);
    if (size > 256) corrupt(fmt::format("{} is {} bytes long", what, size));
    std::string s(size, '\0');
    take(s.data(), size, what);
    return s;
  }
  template <class T>
  void get_column(AlignedColumn<T>& column, std::size_t n, const char* what) {
    take(column.data(), n * sizeof(T), what);
  }
  std::size_t remaining() const { return bytes_.size() - at_; }
  [[noreturn]] void corrupt(const std::string& why) const {
    throw ResumeError(fmt::format("{}: corrupt checkpoint: {}", file_.string(), why));
  }

 private:
  void take(void* to, std::size_t size, const char* what) {
    if (size > remaining()) corrupt(fmt::format("it ends inside {}", what));
    std::memcpy(to, bytes_.data() + at_, size);
    at_ += size;
  }
  std::string_view bytes_;
  const std::filesystem::path& file_;
  std::size_t at_ = 0;
};

}  // namespace

std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash) {
  for (unsigned char c : bytes) {
    hash ^= c;
    hash *= 0x100000001b3ull;
  }
  return hash;
}

std::string encode_checkpoint(const Simulation& sim, std::uint64_t scene_fingerprint) {
  const ParticleStore& s = sim.particles();
  const std::size_t n = s.size();
  std::string body;
  body.reserve(64 + n * kColumnCount * 4);
  const std::string_view version = SEICHE_VERSION;
  put(body, std::uint32_t(version.size()));
  body.append(version);
  put(body, scene_fingerprint);
  put(body, std::int32_t(sim.frame()));
  put(body, sim.time());
  put(body, std::uint64_t(n));
  put(body, kColumnCount);
  for (const FloatColumn* c : {&s.x, &s.y, &s.z, &s.px, &s.py, &s.pz, &s.vx, &s.vy, &s.vz, &s.w})
    put_column(body, *c, n);
  put_column(body, s.phase, n);
  put_column(body, s.id, n);
  const std::span<const float> multipliers = sim.cloth_stretch_multipliers();
  put(body, std::uint64_t(multipliers.size()));
  for (float v : multipliers) put(body, v);

  std::string file;
  file.reserve(kPreambleBytes + body.size());
  file.append(kMagic, sizeof(kMagic));
  put(file, kFormatVersion);
  put(file, std::uint64_t(body.size()));
  put(file, fnv1a64(body));
  file += body;
  return file;
}

Checkpoint read_checkpoint(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw ResumeError(
        fmt::format("{}: cannot open the checkpoint: {}", file.string(), std::strerror(errno)));
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string bytes = std::move(buffer).str();

  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
    throw ResumeError(fmt::format("{}: not a Seiche checkpoint (it does not start with SEICHECP)",
                                  file.string()));
  BodyReader preamble(std::string_view(bytes).substr(sizeof(kMagic)), file);
  const auto format = preamble.get<std::uint32_t>("the format version");
  if (format != kFormatVersion)
    throw ResumeError(fmt::format("{}: checkpoint format version {}, this seiche reads version {}",
                                  file.string(), format, kFormatVersion));
  const auto body_size = preamble.get<std::uint64_t>("the body size");
  const auto checksum = preamble.get<std::uint64_t>("the checksum");
  if (preamble.remaining() != body_size)
    preamble.corrupt(
        fmt::format("the header announces {} bytes of state, the file holds {} (truncated?)",
                    body_size, preamble.remaining()));
  const std::string_view body(bytes.data() + kPreambleBytes, body_size);
  if (fnv1a64(body) != checksum) preamble.corrupt("checksum mismatch (the file was damaged)");

  BodyReader r(body, file);
  Checkpoint cp;
  cp.seiche_version = r.get_string("the seiche version");
  cp.scene_fingerprint = r.get<std::uint64_t>("the scene fingerprint");
  cp.frame = r.get<std::int32_t>("the frame number");
  cp.time = r.get<double>("the time");
  const auto n = r.get<std::uint64_t>("the particle count");
  const auto columns = r.get<std::uint32_t>("the column count");
  if (cp.frame < 0) r.corrupt(fmt::format("negative frame number {}", cp.frame));
  if (columns != kColumnCount)
    r.corrupt(fmt::format("{} columns, expected {}", columns, kColumnCount));
  constexpr std::size_t kBytesPerParticle = kColumnCount * 4;
  if (n > r.remaining() / kBytesPerParticle || n * kBytesPerParticle + 8 > r.remaining())
    r.corrupt(fmt::format("{} particles need {} bytes of columns, the file holds {}", n,
                          n * kBytesPerParticle, r.remaining()));
  ParticleStore& s = cp.state;
  s.resize(n);
  const char* names[] = {"x", "y", "z", "px", "py", "pz", "vx", "vy", "vz", "w"};
  int k = 0;
  for (FloatColumn* c : {&s.x, &s.y, &s.z, &s.px, &s.py, &s.pz, &s.vx, &s.vy, &s.vz, &s.w})
    r.get_column(*c, n, names[k++]);
  r.get_column(s.phase, n, "phase");
  r.get_column(s.id, n, "id");
  const auto m = r.get<std::uint64_t>("the multiplier count");
  if (m > r.remaining() / 4 || m * 4 != r.remaining())
    r.corrupt(fmt::format("{} multipliers need {} bytes, the file holds {}", m, m * 4, r.remaining()));
  cp.stretch_multipliers.resize(m);
  for (float& v : cp.stretch_multipliers) v = r.get<float>("a multiplier");
  std::vector<bool> seen(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t id = s.id[i];
    if (id < 0 || std::uint64_t(id) >= n || seen[std::size_t(id)])
      r.corrupt(
          fmt::format("the ids are not a permutation of 0..{} (at index {}: {})", n - 1, i, id));
    seen[std::size_t(id)] = true;
  }
  return cp;
}

void restore_checkpoint(Simulation& sim, const Checkpoint& cp, std::uint64_t scene_fingerprint,
                        const std::filesystem::path& file) {
  if (cp.scene_fingerprint != scene_fingerprint)
    throw ResumeError(
        fmt::format("{}: this checkpoint belongs to another scene (fingerprint {:016x}, the bake's "
                    "scene has {:016x})",
                    file.string(), cp.scene_fingerprint, scene_fingerprint));
  if (cp.seiche_version != SEICHE_VERSION)
    throw ResumeError(
        fmt::format("{}: written by seiche {}, this is seiche {}: a bake continues bit for bit "
                    "only with the version that started it",
                    file.string(), cp.seiche_version, SEICHE_VERSION));
  if (cp.state.size() != sim.particles().size())
    throw ResumeError(fmt::format("{}: the checkpoint holds {} particles, the scene has {}",
                                  file.string(), cp.state.size(), sim.particles().size()));
  if (cp.stretch_multipliers.size() != sim.cloth_stretch_multipliers().size())
    throw ResumeError(fmt::format("{}: the checkpoint holds {} cloth multipliers, the scene has {}", file.string(),
                                  cp.stretch_multipliers.size(), sim.cloth_stretch_multipliers().size()));
  sim.restore_state(cp.state, cp.frame);
  sim.restore_cloth_stretch_multipliers(cp.stretch_multipliers);
}

}  // namespace seiche
