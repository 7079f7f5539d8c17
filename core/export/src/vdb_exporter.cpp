// Placeholder: replaced by the real exporter.
#include "seiche/export/vdb_exporter.hpp"

namespace seiche {

std::unique_ptr<FrameExporter> make_vdb_exporter(const SceneDef&) { return nullptr; }

}  // namespace seiche
