// What `seiche run` and `seiche bake` tell the user: a progress line while frames are stepped
// (on a terminal one line rewritten in place, with a bar, cut to the terminal's width; in logs
// plain lines, throttled to about one a second, where every line stays), and the summary at the
// end (settings, the pass table, the error of each family).
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "seiche/runner.hpp"
#include "seiche/scene.hpp"

namespace seiche {

inline constexpr int kProgressBarWidth = 20, kMinProgressBar = 5;

class Progress {
 public:
  /// `out` null: quiet. `last_frame`: the frame number the run ends at.
  Progress(std::ostream* out, int last_frame);

  /// Frame `frame` is done, `elapsed` seconds after this session started, which has stepped
  /// `session_frames` frames so far (a resumed bake starts at a later frame). The line reads
  /// "frame k/N  <details>  ETA s<trailer>".
  void frame_done(int frame, double elapsed, int session_frames, std::string_view details,
                  std::string_view trailer = {});
  /// On a terminal, ends the line being rewritten so that other output starts on its own line.
  void end_line();

 private:
  std::ostream* out_;
  int last_frame_;
  bool tty_;
  bool line_open_ = false;
  int bar_cells_ = kProgressBarWidth;  // shrinks to what the terminal leaves, never grows back
  double last_print_ = -1.0;
};

/// The progress line: "frame k/N  <details>  ETA s<trailer>" (what a log gets).
std::string progress_line(int frame, int last_frame, std::string_view details, double eta_seconds,
                          std::string_view trailer);
/// On a terminal `width` columns wide: a bar of `bar_cells` cells in front (none below
/// kMinProgressBar) and the whole cut one column short of the width.
std::string terminal_progress_line(const std::string& line, int frame, int last_frame, int bar_cells, int width);

/// Effective settings, pass table (total and per frame) and the error of each active family.
void print_run_summary(std::ostream& out, const SceneDef& scene, const RunResult& result,
                       const std::vector<std::string>& pipeline);

/// "812 B", "12.3 KB", "4.56 MB", "1.23 GB" (powers of 1000, as file managers show).
std::string format_bytes(std::uint64_t bytes);

}  // namespace seiche
