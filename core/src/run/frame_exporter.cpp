// FrameExporter's default write_frame: the files of encode_frame, each written atomically.
#include "seiche/frame_exporter.hpp"

#include "seiche/output_files.hpp"

namespace seiche {

std::uint64_t FrameExporter::write_frame(const FrameView& frame, const std::filesystem::path& dir) {
  std::uint64_t bytes = 0;
  for (const EncodedFile& f : encode_frame(frame)) {
    write_file_atomically(dir / f.name, f.bytes);
    bytes += f.bytes.size();
  }
  return bytes;
}

}  // namespace seiche
