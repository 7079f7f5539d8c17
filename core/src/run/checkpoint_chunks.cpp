#include "seiche/checkpoint_chunks.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "seiche/checkpoint.hpp"

namespace seiche {

void CheckpointChunks::put(std::string name, std::string bytes) {
  if (find(name) != nullptr)
    throw std::invalid_argument(fmt::format("CheckpointChunks::put: a chunk '{}' exists already", name));
  chunks_.push_back({std::move(name), std::move(bytes)});
}

const CheckpointChunks::Chunk* CheckpointChunks::find(std::string_view name) const {
  for (const Chunk& c : chunks_)
    if (c.name == name) return &c;
  return nullptr;
}

std::string_view CheckpointChunks::get(std::string_view name, std::size_t size) const {
  const Chunk* c = find(name);
  if (c == nullptr)
    throw ResumeError(fmt::format("the checkpoint has no chunk '{}', which this scene needs", name));
  if (c->bytes.size() != size)
    throw ResumeError(
        fmt::format("chunk '{}' holds {} bytes, this scene needs {}", name, c->bytes.size(), size));
  return c->bytes;
}

}  // namespace seiche
