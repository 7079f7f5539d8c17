// Checkpoint files: encoding, verification and restoring. The layout is written at the top of
// checkpoint.hpp; this file keeps the reader as strict as the writer is simple: every size is
// checked before it is used, so a damaged file gives a message, never a crash.
#include "seiche/checkpoint.hpp"

#include <fmt/format.h>

#include <algorithm>
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
constexpr std::uint32_t kFormatVersion = 3;
constexpr std::size_t kPreambleBytes = sizeof(kMagic) + 4 + 8 + 8;

template <class T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

void put_string(std::string& out, std::string_view s) {
  put(out, std::uint32_t(s.size()));
  out.append(s);
}

// Reads the body front to back; running past its end is a truncated (or lying) file.
class BodyReader {
 public:
  BodyReader(std::string_view bytes, const std::filesystem::path& file)
      : bytes_(bytes), file_(file) {}

  template <class T>
  T get(std::string_view what) {
    T value;
    take(&value, sizeof(T), what);
    return value;
  }
  std::string get_string(std::string_view what) {
    const auto size = get<std::uint32_t>(what);
    if (size > 256) corrupt(fmt::format("{} is {} bytes long", what, size));
    std::string s(size, '\0');
    take(s.data(), size, what);
    return s;
  }
  /// `size` bytes into `to`; running past the end is a truncated file.
  void take(void* to, std::size_t size, std::string_view what) {
    if (size > remaining()) corrupt(fmt::format("it ends inside {}", what));
    if (size > 0) std::memcpy(to, bytes_.data() + at_, size);
    at_ += size;
  }
  std::size_t remaining() const { return bytes_.size() - at_; }
  [[noreturn]] void corrupt(const std::string& why) const {
    throw ResumeError(fmt::format("{}: corrupt checkpoint: {}", file_.string(), why));
  }
  [[noreturn]] void refuse(const std::string& why) const {
    throw ResumeError(fmt::format("{}: {}", file_.string(), why));
  }

 private:
  std::string_view bytes_;
  const std::filesystem::path& file_;
  std::size_t at_ = 0;
};

// The State columns by name, into a store of the file's particle count. A name the built-in
// table does not have becomes a State column of its own (a family's, for restore_checkpoint to
// match); every built-in State column must be there.
void read_columns(BodyReader& r, ParticleStore& s, std::uint32_t count) {
  std::vector<std::string> read;
  for (std::uint32_t k = 0; k < count; ++k) {
    std::string name = r.get_string("a column name");
    const auto type = r.get<std::uint8_t>(fmt::format("the type of column '{}'", name));
    if (type > std::uint8_t(ColumnType::I32)) r.corrupt(fmt::format("column '{}' has type {}", name, type));
    if (std::find(read.begin(), read.end(), name) != read.end())
      r.corrupt(fmt::format("column '{}' appears twice", name));
    StoreColumn* column = s.find(name);
    if (column == nullptr) {
      switch (ColumnType(type)) {
        case ColumnType::F32: s.add_column<float>(name, ColumnKind::State); break;
        case ColumnType::U32: s.add_column<std::uint32_t>(name, ColumnKind::State); break;
        case ColumnType::I32: s.add_column<std::int32_t>(name, ColumnKind::State); break;
      }
      column = s.find(name);
    }
    if (column->kind != ColumnKind::State)
      r.refuse(fmt::format("the checkpoint holds column '{}', which this seiche does not checkpoint", name));
    if (column->type() != ColumnType(type))
      r.corrupt(fmt::format("column '{}' is {}, this seiche keeps it as {}", name,
                            column_type_name(ColumnType(type)), column_type_name(column->type())));
    r.take(column->raw(), s.size() * StoreColumn::kElementBytes, fmt::format("column '{}'", name));
    read.push_back(std::move(name));
  }
  for (const StoreColumn& c : s.columns())
    if (c.kind == ColumnKind::State && std::find(read.begin(), read.end(), c.name) == read.end())
      r.refuse(fmt::format("the checkpoint has no column '{}'", c.name));
}

void read_chunks(BodyReader& r, CheckpointChunks& chunks) {
  const auto count = r.get<std::uint32_t>("the chunk count");
  for (std::uint32_t k = 0; k < count; ++k) {
    std::string name = r.get_string("a chunk name");
    const auto size = r.get<std::uint64_t>(fmt::format("the size of chunk '{}'", name));
    if (size > r.remaining())
      r.corrupt(fmt::format("it ends inside chunk '{}' ({} bytes announced, {} left)", name, size,
                            r.remaining()));
    if (chunks.find(name) != nullptr) r.corrupt(fmt::format("chunk '{}' appears twice", name));
    std::string bytes(size, '\0');
    r.take(bytes.data(), size, fmt::format("chunk '{}'", name));
    chunks.put(std::move(name), std::move(bytes));
  }
}

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
  std::vector<const StoreColumn*> state;
  for (const StoreColumn& c : s.columns())
    if (c.kind == ColumnKind::State) state.push_back(&c);
  const CheckpointChunks chunks = sim.family_state();
  body.reserve(256 + n * state.size() * StoreColumn::kElementBytes);
  put_string(body, SEICHE_VERSION);
  put(body, scene_fingerprint);
  put(body, std::int32_t(sim.frame()));
  put(body, sim.time());
  put(body, std::uint64_t(n));
  put(body, std::uint32_t(state.size()));
  for (const StoreColumn* c : state) {
    put_string(body, c->name);
    put(body, std::uint8_t(c->type()));
    body.append(c->raw(), n * StoreColumn::kElementBytes);
  }
  put(body, std::uint32_t(chunks.all().size()));
  for (const CheckpointChunks::Chunk& c : chunks.all()) {
    put_string(body, c.name);
    put(body, std::uint64_t(c.bytes.size()));
    body += c.bytes;
  }

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
  // Sizes before allocations: every column holds n values of 4 bytes.
  constexpr std::size_t kBytes = StoreColumn::kElementBytes;
  if (columns == 0 || n > r.remaining() / kBytes / columns)
    r.corrupt(fmt::format("{} columns of {} particles need {} bytes, the file holds {}", columns, n,
                          columns * n * kBytes, r.remaining()));
  ParticleStore& s = cp.state;
  s.resize(n);
  read_columns(r, s, columns);
  read_chunks(r, cp.chunks);
  if (r.remaining() != 0) r.corrupt(fmt::format("{} bytes after the last chunk", r.remaining()));
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
  auto refuse = [&](const std::string& why) { throw ResumeError(fmt::format("{}: {}", file.string(), why)); };
  // The State columns of the checkpoint are exactly those of this store (built-ins and the
  // scene's families' own), and so are the chunks of the families.
  const ParticleStore& store = sim.particles();
  for (const StoreColumn& c : cp.state.columns()) {
    if (c.kind != ColumnKind::State) continue;
    const StoreColumn* mine = store.find(c.name);
    if (mine == nullptr || mine->kind != ColumnKind::State || mine->type() != c.type())
      refuse(fmt::format("the checkpoint holds column '{}' that this seiche does not know", c.name));
  }
  for (const StoreColumn& c : store.columns()) {
    const StoreColumn* saved = cp.state.find(c.name);
    if (c.kind == ColumnKind::State && (saved == nullptr || saved->kind != ColumnKind::State))
      refuse(fmt::format("the checkpoint has no column '{}', which this scene needs", c.name));
  }
  const CheckpointChunks expected = sim.family_state();
  for (const CheckpointChunks::Chunk& c : cp.chunks.all())
    if (expected.find(c.name) == nullptr)
      refuse(fmt::format("the checkpoint holds chunk '{}' that this seiche does not know", c.name));
  for (const CheckpointChunks::Chunk& c : expected.all())
    if (cp.chunks.find(c.name) == nullptr)
      refuse(fmt::format("the checkpoint has no chunk '{}', which this scene needs", c.name));
  sim.restore_state(cp.state, cp.frame);
  try {
    sim.restore_family_state(cp.chunks);  // each family checks its chunks' sizes
  } catch (const ResumeError& e) {
    refuse(e.what());
  }
}

}  // namespace seiche
