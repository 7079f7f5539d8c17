#include "seiche/frame_metrics.hpp"

#include <algorithm>

namespace seiche {

namespace {

template <class Get>
std::optional<RunError> summarize(std::span<const FrameMetrics> frames, Get get) {
  if (frames.empty() || !get(frames.front())) return std::nullopt;
  RunError e;
  for (const FrameMetrics& m : frames) {
    const auto [mean, max] = *get(m);
    e.mean += mean;
    e.max = std::max(e.max, max);
  }
  e.mean /= double(frames.size());
  return e;
}

using Pair = std::optional<std::pair<double, double>>;

}  // namespace

RunErrors summarize_errors(std::span<const FrameMetrics> frames) {
  RunErrors r;
  r.density = summarize(frames, [](const FrameMetrics& m) {
    return m.fluid ? Pair{{m.fluid->mean, m.fluid->max}} : std::nullopt;
  });
  r.distance = summarize(frames, [](const FrameMetrics& m) {
    return m.distance ? Pair{{m.distance->mean, m.distance->max}} : std::nullopt;
  });
  r.strain = summarize(frames, [](const FrameMetrics& m) {
    return m.cloth ? Pair{{m.cloth->strain_mean, m.cloth->strain_max}} : std::nullopt;
  });
  r.bending = summarize(frames, [](const FrameMetrics& m) {
    return m.cloth ? Pair{{m.cloth->bending_mean, m.cloth->bending_max}} : std::nullopt;
  });
  return r;
}

}  // namespace seiche
