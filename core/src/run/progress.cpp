#include "progress.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

#include "seiche/kernels/simd_info.hpp"

namespace seiche {

namespace {

// The terminal's width in columns (stderr's), or 80 when it does not say.
int terminal_width() {
  winsize size{};
  if (::ioctl(2, TIOCGWINSZ, &size) == 0 && size.ws_col > 0) return size.ws_col;
  return 80;
}

}  // namespace

std::string progress_line(int frame, int last_frame, std::string_view details, double eta_seconds,
                          std::string_view trailer) {
  return fmt::format("frame {}/{}  {}  ETA {:.1f} s{}", frame, last_frame, details, eta_seconds, trailer);
}

std::string terminal_progress_line(const std::string& line, int frame, int last_frame, int bar_cells, int width) {
  std::string out = line;
  if (bar_cells >= kMinProgressBar) {
    const double share = last_frame > 0 ? std::clamp(double(frame) / last_frame, 0.0, 1.0) : 1.0;
    const int done = int(std::lround(bar_cells * share));
    out = fmt::format("[{}{}] {}", std::string(std::size_t(done), '#'), std::string(std::size_t(bar_cells - done), '-'),
                      line);
  }
  // One column short of the width: a line that fills it wraps on some terminals, and a wrapped
  // line cannot be rewritten in place.
  const std::size_t fits = std::size_t(std::max(width - 1, 1));
  if (out.size() > fits) out.resize(fits);
  return out;
}

Progress::Progress(std::ostream* out, int last_frame)
    : out_(out), last_frame_(last_frame), tty_(out && ::isatty(2)) {}

void Progress::frame_done(int frame, double elapsed, int session_frames, std::string_view details,
                          std::string_view trailer) {
  if (!out_) return;
  const bool last = frame == last_frame_;
  if (!tty_ && !last && session_frames != 1 && elapsed - last_print_ < 1.0) return;
  last_print_ = elapsed;
  const double eta = elapsed / std::max(session_frames, 1) * (last_frame_ - frame);
  std::string line = progress_line(frame, last_frame_, details, eta, trailer);
  if (tty_) {
    // The bar takes what the line leaves of the width, and only ever shrinks, so that it does
    // not jump as the numbers change length; below kMinProgressBar cells it goes.
    const int width = terminal_width();
    bar_cells_ = std::min(bar_cells_, std::max(width - 1 - int(line.size()) - 3, 0));  // "[", "] "
    line = terminal_progress_line(line, frame, last_frame_, bar_cells_, width);
    *out_ << "\r" << line << "\x1b[K" << (last ? "\n" : "") << std::flush;
    line_open_ = !last;
  } else {
    *out_ << line << "\n" << std::flush;
  }
}

void Progress::end_line() {
  if (out_ && line_open_) *out_ << "\n" << std::flush;
  line_open_ = false;
}

void print_run_summary(std::ostream& out, const SceneDef& scene, const RunResult& r,
                       const std::vector<std::string>& pipeline) {
  fmt::print(out,
             "\n{}: {} frames, {} particles, {} substeps x {} iterations, {} threads, {:.2f} s\n",
             scene.name, r.frames, r.particles, scene.solver.substeps, scene.solver.iterations,
             r.threads, r.wall_seconds);
  fmt::print(out, "pipeline: {}\n", fmt::join(pipeline, " -> "));
  fmt::print(out, "simd: {}\n\n", kernels::simd_description());
  double total = 0.0;
  for (const auto& e : r.timer.entries()) total += e.total_seconds;
  fmt::print(out, "{:<16} {:>10} {:>10} {:>7}\n", "pass", "total ms", "ms/frame", "share");
  for (const auto& e : r.timer.entries())
    fmt::print(out, "{:<16} {:>10.1f} {:>10.2f} {:>6.1f}%\n", e.name, e.total_seconds * 1e3,
               e.total_seconds * 1e3 / std::max(r.frames, 1),
               total > 0 ? 100.0 * e.total_seconds / total : 0.0);
  if (r.metrics.empty()) return;
  // Error of each active constraint family over the run (summarize_errors).
  fmt::print(out, "\n{:<16} {:>10} {:>10}\n", "error", "mean", "max");
  for (const ErrorRow& e : summarize_errors(r.metrics)) {
    if (e.unit == ErrorUnit::Radians) {  // an angle: shown in degrees, not percent
      constexpr double kDegrees = 180.0 / 3.14159265358979323846;
      fmt::print(out, "{:<16} {:>8.3f}deg {:>7.3f}deg\n", e.label, kDegrees * e.mean, kDegrees * e.max);
    } else {
      fmt::print(out, "{:<16} {:>9.3f}% {:>9.3f}%\n", e.label, 100.0 * e.mean, 100.0 * e.max);
    }
  }
  // Extra iterations the density tolerance asked for.
  double iterations = 0.0;
  int iterations_max = 0;
  for (const FrameMetrics& m : r.metrics) {
    iterations += m.iterations_mean;
    iterations_max = std::max(iterations_max, m.iterations_max);
  }
  if (iterations_max > scene.solver.iterations)
    fmt::print(out, "\niterations per substep: {:.2f} on average, {} at most (density tolerance {:.3g} %)\n",
               iterations / double(r.metrics.size()), iterations_max, 100.0 * scene.solver.density_tolerance);
  const FrameMetrics& last = r.metrics.back();
  fmt::print(out, "\nlast frame: kinetic energy {:.4g} J, max speed {:.3g} m/s\n",
             last.kinetic_energy, last.max_speed);
}

std::string format_bytes(std::uint64_t bytes) {
  if (bytes < 1000) return fmt::format("{} B", bytes);
  const char* units[] = {"KB", "MB", "GB", "TB"};
  double value = double(bytes) / 1000.0;
  int unit = 0;
  while (value >= 1000.0 && unit < 3) value /= 1000.0, ++unit;
  return fmt::format("{:.{}f} {}", value, value < 10 ? 2 : value < 100 ? 1 : 0, units[unit]);
}

}  // namespace seiche
