// The JSON run report (`seiche run --report FILE`): the effective settings, then per frame the
// wall time of every pass, the particle count, the error of each active constraint family,
// kinetic energy, max speed and the count of non-finite values; for a bake also the export time
// and bytes written per frame.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "seiche/frame_metrics.hpp"
#include "seiche/pass_timer.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class RunReport {
 public:
  RunReport(const SceneDef& scene, std::size_t particles, int frames, int threads,
            const std::vector<std::string>& pipeline);
  void add_frame(const FrameMetrics& m, const PassTimer& timer);
  /// A bake's output for the frame added last: time spent writing its files (and checkpoint)
  /// and the bytes written.
  void add_frame_output(double export_ms, std::uint64_t bytes);
  void set_error(const std::string& message);
  /// settings.frames, for a report whose frames are stepped one call at a time (the Python API's
  /// Simulation: the frames stepped so far).
  void set_frames(int frames);
  std::string dump() const { return doc_.dump(2) + "\n"; }

 private:
  nlohmann::json doc_;
};

}  // namespace seiche
