#include "seiche/frame_metrics.hpp"

#include <algorithm>

namespace seiche {

const ErrorRow* find_error(std::span<const ErrorRow> rows, std::string_view key) {
  for (const ErrorRow& r : rows)
    if (r.key == key) return &r;
  return nullptr;
}

RunErrors summarize_errors(std::span<const FrameMetrics> frames) {
  RunErrors run;
  std::vector<std::size_t> frames_with;  // per row of `run`: the frames that had it
  for (const FrameMetrics& m : frames)
    for (const ErrorRow& e : m.errors) {
      auto it = std::find_if(run.begin(), run.end(), [&](const ErrorRow& r) { return r.key == e.key; });
      if (it == run.end()) {
        run.push_back({e.key, e.label, e.unit, 0.0, 0.0});
        frames_with.push_back(0);
        it = run.end() - 1;
      }
      it->mean += e.mean;
      it->max = std::max(it->max, e.max);
      ++frames_with[std::size_t(it - run.begin())];
    }
  for (std::size_t k = 0; k < run.size(); ++k) run[k].mean /= double(frames_with[k]);
  return run;
}

}  // namespace seiche
